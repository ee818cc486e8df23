//! Lists read from JSON with their cap enforced while they are read: the
//! item past the cap stops the parser, so a file of millions of entries is
//! refused after `MAX` of them, not after all are held.

use std::fmt;
use std::marker::PhantomData;

use serde::de::{Deserialize, Deserializer, SeqAccess, Visitor};

struct CappedVisitor<T, const MAX: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const MAX: usize> Visitor<'de> for CappedVisitor<T, MAX> {
    type Value = Vec<T>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a list of at most {MAX} items")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
        // The size hint is the file's word: trusted only up to the cap.
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(MAX).min(4096));
        while let Some(item) = seq.next_element()? {
            if out.len() == MAX {
                return Err(serde::de::Error::custom(format!(
                    "a list longer than its cap of {MAX} items"
                )));
            }
            out.push(item);
        }
        Ok(out)
    }
}

/// A `Vec<T>` of at most `MAX` items, for `#[serde(deserialize_with = ...)]`.
pub fn vec<'de, D: Deserializer<'de>, T: Deserialize<'de>, const MAX: usize>(
    d: D,
) -> Result<Vec<T>, D::Error> {
    d.deserialize_seq(CappedVisitor::<T, MAX>(PhantomData))
}

#[cfg(test)]
mod tests {
    #[derive(serde::Deserialize, Debug)]
    struct Three {
        #[serde(deserialize_with = "super::vec::<_, _, 3>")]
        items: Vec<u8>,
    }

    #[test]
    fn the_item_past_the_cap_stops_the_parser() {
        assert_eq!(
            serde_json::from_str::<Three>(r#"{"items": [1, 2, 3]}"#)
                .expect("at the cap")
                .items,
            [1, 2, 3]
        );
        // Refused at the fourth item: the broken tail is never reached.
        let e = serde_json::from_str::<Three>(r#"{"items": [1, 2, 3, 4, 5 broken"#)
            .expect_err("over the cap");
        assert!(e.to_string().contains("cap of 3"), "{e}");
    }
}
