//! Lists an .mcap's channels and messages (a development aid).
fn main() {
    let path = std::env::args().nth(1).expect("path");
    let cut: usize = std::env::args()
        .nth(2)
        .and_then(|v| v.parse().ok())
        .unwrap_or(usize::MAX);
    let mut bytes = std::fs::read(&path).expect("read");
    bytes.truncate(cut.min(bytes.len()));
    match upetrack_recordings::mcap::Mcap::open(bytes) {
        Ok(m) => {
            println!("{:?}", m.warnings);
            for (id, c) in &m.channels {
                println!("{id} {c:?}");
            }
            println!("{} messages", m.messages.len());
        }
        Err(e) => println!("error {e}"),
    }
}
