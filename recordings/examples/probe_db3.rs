//! Lists a .db3's topics and messages (a development aid).
fn main() {
    let path = std::env::args().nth(1).expect("path");
    let f = upetrack_recordings::FileBytes::open(std::path::Path::new(&path)).expect("open");
    let mut db = upetrack_recordings::rosbag2::Rosbag2::open(f).expect("db3");
    for t in &db.topics {
        println!("{} {} {} {}", t.id, t.name, t.msg_type, t.serialization);
    }
    let ms = db.messages.clone();
    for m in &ms {
        let d = db.read(m).expect("read");
        println!("{} {} {}", m.topic, m.time_ns, d.len());
    }
}
