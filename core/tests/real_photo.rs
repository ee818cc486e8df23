//! Segmentation and initialisation on a real D435 photo of a rope (TrackDLO's
//! `rope.png`): the mask covers the rope and nothing else, and the ordered
//! centre line runs from one cyan cap to the other.

use upetrack::math::Vec2;
use upetrack::perception::initialisation::{find_centre_line, largest_blob};
use upetrack::perception::segmentation::segment;
use upetrack::{Frame, HsvRange};

fn load_rope() -> (u32, u32, Vec<u8>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/trackdlo/rope.png"
    );
    let file = std::fs::File::open(path).expect("tests/data/trackdlo/rope.png");
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    let channels = info.color_type.samples();
    let rgb: Vec<u8> = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    (info.width, info.height, rgb)
}

#[test]
fn trackdlo_rope_photo_is_segmented_and_ordered_cap_to_cap() {
    let (w, h, rgb) = load_rope();
    assert_eq!((w, h), (640, 480));
    let depth = vec![0u16; (w * h) as usize];
    let frame = Frame::new(w, h, &rgb, &depth, 0.001).expect("frame");
    let mask = segment(&frame, &HsvRange::default(), &[]);

    // The rope is one long blob; the white table and its specks are not rope.
    let blob = largest_blob(&mask);
    let total = mask.count();
    assert!(blob.len() > 8_000, "rope blob has {} pixels", blob.len());
    assert!(
        blob.len() as f64 > 0.97 * total as f64,
        "{} of {} mask pixels outside the rope",
        total - blob.len(),
        total
    );
    // Nothing segmented far from the rope: the bottom part is table.
    for v in 300..480 {
        for u in 0..640 {
            assert!(!mask.get(u, v), "table pixel ({u}, {v}) segmented");
        }
    }

    let line = find_centre_line(&mask, 150).expect("centre line");
    let (first, last) = (line[0], line[line.len() - 1]);
    let upper_cap = Vec2::new(557.0, 130.0);
    let lower_cap = Vec2::new(545.0, 240.0);
    let (a, b) = if (first - upper_cap).norm() < (first - lower_cap).norm() {
        (upper_cap, lower_cap)
    } else {
        (lower_cap, upper_cap)
    };
    assert!(
        (first - a).norm() < 20.0,
        "first end {first:?} not at a cap"
    );
    assert!(
        (last - b).norm() < 20.0,
        "last end {last:?} not at the other cap"
    );
    // The U's bend: the rope's outer edge is near x = 47 and it is about
    // 20 px thick there, so the centre line must reach x < 65.
    let leftmost = line.iter().map(|p| p.x).fold(f64::MAX, f64::min);
    assert!(leftmost < 65.0, "centre line stops at x = {leftmost}");
    // Every centre-line point lies on the rope.
    for p in &line {
        let (u, v) = (p.x.round() as i64, p.y.round() as i64);
        let near = (-2..=2).any(|dv| (-2..=2).any(|du| mask.get(u + du, v + dv)));
        assert!(near, "centre line point {p:?} is off the rope");
    }
    // Consecutive points are adjacent pixels: the line is one ordered chain.
    for w in line.windows(2) {
        assert!(
            (w[1] - w[0]).norm() < 1.5,
            "gap between {:?} and {:?}",
            w[0],
            w[1]
        );
    }
}
