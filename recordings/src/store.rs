//! The container under a recording, whichever it is: a ROS1 bag, a rosbag2
//! SQLite database or an MCAP file, seen as one list of topics and one
//! time-ordered list of messages, each read on demand.

use std::collections::BTreeMap;

use crate::bytes::ByteSource;
use crate::error::RecordingError;
use crate::mcap::{self, Mcap};
use crate::ros_msgs::Wire;
use crate::rosbag1::{self, Bag};
use crate::rosbag2::{self, Rosbag2};
use crate::sqlite;

/// A topic with its message type as `package/Type` (ROS 2's `/msg/` dropped).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    /// Topic name.
    pub name: String,
    /// Message type, as `sensor_msgs/Image`.
    pub msg_type: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum At {
    Bag(rosbag1::MessageRef),
    Db(rosbag2::Message),
    Mcap(mcap::MessageRef),
}

/// One message: its topic (an index into [`Store::topics`]), its time and its place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Msg {
    /// Index of its topic.
    pub topic: usize,
    /// Recording time, nanoseconds.
    pub time_ns: u64,
    at: At,
}

enum Inner<R: ByteSource> {
    Bag(Bag<R>),
    Db(Rosbag2<R>),
    Mcap(Mcap<R>),
}

/// An opened container.
pub struct Store<R: ByteSource> {
    inner: Inner<R>,
    /// Every topic, once.
    pub topics: Vec<Topic>,
    /// Every message, in time order.
    pub messages: Vec<Msg>,
    /// How its messages are serialised.
    pub wire: Wire,
}

/// `true` when `head` starts like a container this crate reads.
pub fn is_container(head: &[u8]) -> bool {
    rosbag1::is_bag(head) || sqlite::is_sqlite(head) || mcap::is_mcap(head)
}

fn topic_index(topics: &mut Vec<Topic>, name: &str, msg_type: &str) -> usize {
    let msg_type = msg_type.replacen("/msg/", "/", 1);
    if let Some(i) = topics.iter().position(|t| t.name == name) {
        return i;
    }
    topics.push(Topic {
        name: name.to_string(),
        msg_type,
    });
    topics.len() - 1
}

/// A container's messages as [`Msg`]s: `ids` maps the container's topic id to
/// the topic's index in [`Store::topics`]; a message of an unknown id is left out.
fn listed<K: Ord>(ids: &BTreeMap<K, usize>, msgs: impl Iterator<Item = (K, u64, At)>) -> Vec<Msg> {
    msgs.filter_map(|(k, time_ns, at)| {
        Some(Msg {
            topic: *ids.get(&k)?,
            time_ns,
            at,
        })
    })
    .collect()
}

impl<R: ByteSource> Store<R> {
    /// Opens a ROS1 bag, a rosbag2 `.db3` or an `.mcap`, told apart by their first bytes.
    pub fn open(mut src: R) -> Result<Self, RecordingError> {
        let mut head = [0u8; 16];
        let n = head.len().min(src.len() as usize);
        src.read_at(0, &mut head[..n])?;
        let mut topics = Vec::new();
        // Each container's own list is moved into the store's, never held twice.
        if mcap::is_mcap(&head[..n]) {
            let mut m = Mcap::open(src)?;
            let mut wire = None;
            for c in m.channels.values() {
                let w = match c.encoding.as_str() {
                    "cdr" => Wire::Cdr,
                    "ros1" => Wire::Ros1,
                    other => {
                        return Err(RecordingError::UnknownFormat {
                            reason: format!(
                                "channel {} is encoded as `{other}` (cdr and ros1 are read)",
                                c.topic
                            ),
                        })
                    }
                };
                if wire.is_some_and(|x| x != w) {
                    return Err(RecordingError::UnknownFormat {
                        reason: "an MCAP file mixing ROS1 and CDR messages".into(),
                    });
                }
                wire = Some(w);
            }
            let ids: BTreeMap<u16, usize> = m
                .channels
                .iter()
                .map(|(id, c)| (*id, topic_index(&mut topics, &c.topic, &c.schema)))
                .collect();
            let messages = listed(
                &ids,
                std::mem::take(&mut m.messages)
                    .into_iter()
                    .map(|r| (r.channel, r.time_ns, At::Mcap(r))),
            );
            return Ok(Self {
                inner: Inner::Mcap(m),
                topics,
                messages,
                wire: wire.unwrap_or(Wire::Cdr),
            });
        }
        if sqlite::is_sqlite(&head[..n]) {
            let mut db = Rosbag2::open(src)?;
            if let Some(t) = db.topics.iter().find(|t| t.serialization != "cdr") {
                return Err(RecordingError::UnknownFormat {
                    reason: format!(
                        "topic {} is serialised as `{}` (only cdr is read)",
                        t.name, t.serialization
                    ),
                });
            }
            let ids: BTreeMap<i64, usize> = db
                .topics
                .iter()
                .map(|t| (t.id, topic_index(&mut topics, &t.name, &t.msg_type)))
                .collect();
            let messages = listed(
                &ids,
                std::mem::take(&mut db.messages)
                    .into_iter()
                    .map(|m| (m.topic, m.time_ns, At::Db(m))),
            );
            return Ok(Self {
                inner: Inner::Db(db),
                topics,
                messages,
                wire: Wire::Cdr,
            });
        }
        let mut bag = Bag::open(src)?;
        let ids: BTreeMap<u32, usize> = bag
            .connections
            .values()
            .map(|c| (c.id, topic_index(&mut topics, &c.topic, &c.msg_type)))
            .collect();
        let messages = listed(
            &ids,
            std::mem::take(&mut bag.messages)
                .into_iter()
                .map(|m| (m.conn, m.time_ns, At::Bag(m))),
        );
        Ok(Self {
            inner: Inner::Bag(bag),
            topics,
            messages,
            wire: Wire::Ros1,
        })
    }

    /// What the container reader could not read.
    pub fn warnings(&self) -> &[String] {
        match &self.inner {
            Inner::Bag(b) => &b.warnings,
            Inner::Db(_) => &[],
            Inner::Mcap(m) => &m.warnings,
        }
    }

    /// The serialised message `m`.
    pub fn read(&mut self, m: &Msg) -> Result<Vec<u8>, RecordingError> {
        match (&mut self.inner, &m.at) {
            (Inner::Bag(b), At::Bag(r)) => b.read(r),
            (Inner::Db(d), At::Db(r)) => d.read(r),
            (Inner::Mcap(m), At::Mcap(r)) => m.read(r),
            _ => Err(RecordingError::corrupt(0, "a message of another container")),
        }
    }

    /// The topic named `name`, if any.
    pub fn topic(&self, name: &str) -> Option<&Topic> {
        self.topics.iter().find(|t| t.name == name)
    }

    /// The messages on topic `name`, in time order.
    pub fn on(&self, name: &str) -> Vec<Msg> {
        let Some(i) = self.topics.iter().position(|t| t.name == name) else {
            return Vec::new();
        };
        self.messages
            .iter()
            .filter(|m| m.topic == i)
            .copied()
            .collect()
    }

    /// The first message on topic `name`, read.
    pub fn first(&mut self, name: &str) -> Result<Option<Vec<u8>>, RecordingError> {
        match self.on(name).first() {
            Some(m) => Ok(Some(self.read(m)?)),
            None => Ok(None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_container_is_told_by_its_first_bytes() {
        assert!(is_container(b"#ROSBAG V2.0\n"));
        assert!(is_container(b"SQLite format 3\0"));
        assert!(is_container(b"\x89MCAP0\r\n"));
        assert!(!is_container(b"#ROSBAG V1.2\n"));
        assert!(!is_container(b"PK\x03\x04"));
        assert!(!is_container(b""));
    }
}
