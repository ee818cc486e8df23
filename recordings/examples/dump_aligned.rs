//! Writes each frame's aligned depth as raw little-endian u16 (a development aid).
fn main() {
    let mut a = std::env::args().skip(1);
    let path = a.next().expect("recording");
    let out = a.next().expect("prefix");
    let f = upetrack_recordings::FileBytes::open(std::path::Path::new(&path)).expect("open");
    let mut rec = upetrack_recordings::Recording::open(f, &Default::default()).expect("rec");
    for i in 0..rec.len() {
        let fr = rec.frame(i).expect("frame");
        let b: Vec<u8> = fr.depth.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(format!("{out}_{i}.raw"), b).expect("write");
    }
}
