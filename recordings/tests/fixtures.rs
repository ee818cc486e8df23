//! The reader on recordings made by the real writers (`scripts/make_recordings.py`):
//! librealsense 2.55's recorder (ROS1 bag), librealsense 2.59's (rosbag2
//! `.db3`), and `rosbags` in realsense-ros's ROS1 and ROS 2 layouts.

use std::path::{Path, PathBuf};

use upetrack_recordings::align::AlignArithmetic;
use upetrack_recordings::recording::Layout;
use upetrack_recordings::{FileBytes, Recording, RecordingError, RecordingOptions};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/recordings")
        .join(name)
}

fn open(name: &str) -> Recording<FileBytes> {
    let bytes = FileBytes::open(&fixture(name)).expect("fixture exists");
    Recording::open(bytes, &RecordingOptions::default()).expect("opens")
}

/// A PNG of the fixtures: (width, height, 8-bit channels or 16-bit values widened).
fn png(path: &Path) -> (u32, u32, Vec<u16>) {
    let file = std::fs::File::open(path).expect("png exists");
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0u8; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    let data = &buf[..info.buffer_size()];
    let values = if info.bit_depth == png::BitDepth::Sixteen {
        data.chunks_exact(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect()
    } else {
        data.iter().map(|&b| u16::from(b)).collect()
    };
    (info.width, info.height, values)
}

#[test]
fn librealsense_recordings_streams_intrinsics_and_units() {
    for (name, suffix) in [
        ("librealsense.bag", ""),
        ("librealsense.db3", "/compressed"),
    ] {
        let rec = open(name);
        let depth_suffix = if suffix.is_empty() {
            ""
        } else {
            "/compressedDepth"
        };
        assert_eq!(
            rec.color.topic,
            format!("/device_0/sensor_1/Color_0/image/data{suffix}")
        );
        assert_eq!(
            rec.depth.topic,
            format!("/device_0/sensor_0/Depth_0/image/data{depth_suffix}")
        );
        check_librealsense(&rec, name);
    }
}

fn check_librealsense(rec: &Recording<FileBytes>, name: &str) {
    println!("{name}");
    assert_eq!(rec.layout, Layout::Librealsense);
    assert_eq!(rec.len(), 8);
    assert_eq!((rec.unpaired_color, rec.unpaired_depth), (0, 0));
    let d = rec.depth.intrinsics;
    assert_eq!((d.width, d.height, d.fx, d.ppx), (320, 240, 192.0, 161.3));
    let c = rec.color.intrinsics;
    assert_eq!((c.width, c.height, c.fx), (320, 240, 307.5));
    assert!((rec.depth_units - 0.001).abs() < 1e-9);
    assert_eq!(rec.color.fps, 30.0);
    let ex = rec.depth_to_color.expect("extrinsics");
    assert!((ex.translation[0] - 0.0148).abs() < 1e-6, "{ex:?}");
    // The recorded 0.3 degree turn about y, column-major: r[6] = sin(a).
    assert!(
        (ex.rotation[6] - 0.3f32.to_radians().sin()).abs() < 1e-6,
        "{ex:?}"
    );
    assert!(rec.warnings().is_empty(), "{:?}", rec.warnings());
}

#[test]
fn alignment_matches_pyrealsense2_align_on_99_percent_of_pixels() {
    for (name, golden) in [
        ("librealsense.bag", "golden"),
        ("librealsense.db3", "golden_db3"),
    ] {
        aligned_like_pyrealsense2(name, golden);
    }
}

/// Share of valid pixels within 1 unit of pyrealsense2's golden, aligned with `align`.
fn agreement(name: &str, golden_dir: &str, align: Option<AlignArithmetic>) -> f64 {
    let bytes = FileBytes::open(&fixture(name)).expect("fixture exists");
    let options = RecordingOptions {
        align,
        ..RecordingOptions::default()
    };
    let mut rec = Recording::open(bytes, &options).expect("opens");
    let mut total = 0usize;
    let mut within = 0usize;
    for i in 0..rec.len() {
        let f = rec.frame(i).expect("frame decodes");
        let (w, h, golden) = png(&fixture(&format!("{golden_dir}/aligned_{i:06}.png")));
        assert_eq!((w, h), (f.width, f.height));
        for (&ours, &theirs) in f.depth.iter().zip(&golden) {
            if ours == 0 && theirs == 0 {
                continue;
            }
            total += 1;
            if ours.abs_diff(theirs) <= 1 {
                within += 1;
            }
        }
    }
    assert!(
        total > 8 * 320 * 200,
        "{total} valid pixels: too few to judge"
    );
    let share = within as f64 / total as f64;
    println!("{name} ({align:?}): aligned pixels within 1 unit of pyrealsense2: {within}/{total} = {share:.5}");
    share
}

fn aligned_like_pyrealsense2(name: &str, golden_dir: &str) {
    let share = agreement(name, golden_dir, None);
    assert!(share >= 0.99, "{share}");
    // The other aligner's arithmetic would not do: the check tells them apart.
    let own = Recording::open(
        FileBytes::open(&fixture(name)).expect("fixture"),
        &RecordingOptions::default(),
    )
    .expect("opens")
    .align;
    let other = match own {
        AlignArithmetic::X86Sse => AlignArithmetic::Portable,
        AlignArithmetic::Portable => AlignArithmetic::X86Sse,
    };
    let wrong = agreement(name, golden_dir, Some(other));
    assert!(wrong < 0.99, "{name}: {other:?} also agrees on {wrong}");
}

#[test]
fn ros_bags_give_back_the_frames_that_were_written() {
    for (name, frames) in [
        ("ros_bz2.bag", 8),
        ("ros_lz4.bag", 4),
        ("ros_none.bag", 3),
        ("ros2_png.db3", 8),
        ("ros2_raw.db3", 3),
        ("ros2_png.mcap", 8),
        ("ros2_raw.mcap", 3),
    ] {
        let mut rec = open(name);
        assert_eq!(rec.layout, Layout::Ros, "{name}");
        assert_eq!(rec.len(), frames, "{name}");
        assert!(rec.depth_to_color.is_none());
        for i in 0..frames {
            let f = rec.frame(i).expect("frame");
            let (_, _, color) = png(&fixture(&format!("reference/color/{i:06}.png")));
            let (_, _, depth) = png(&fixture(&format!("reference/depth/{i:06}.png")));
            assert!(
                f.color
                    .iter()
                    .map(|&c| u16::from(c))
                    .eq(color.iter().copied()),
                "{name} frame {i}: colour differs (bgr8 not swapped?)"
            );
            assert_eq!(f.depth, depth, "{name} frame {i}: depth differs");
        }
    }
}

#[test]
fn truncated_recording_plays_the_frames_before_the_cut() {
    // librealsense writes through ROS's own bag library, which repeats each
    // connection inside the chunks, so a bag cut before its index still names its topics.
    let bytes = std::fs::read(fixture("librealsense.bag")).expect("fixture");
    let cut = bytes[..bytes.len() * 3 / 4].to_vec();
    let mut rec = Recording::open(cut, &RecordingOptions::default()).expect("opens by scanning");
    assert!(!rec.warnings().is_empty());
    assert!(rec.len() >= 3 && rec.len() < 8, "{} frames", rec.len());
    rec.frame(0).expect("first frame still decodes");
}

#[test]
fn mcap_without_its_summary_is_scanned() {
    let bytes = std::fs::read(fixture("ros2_png.mcap")).expect("fixture");
    let cut = bytes[..bytes.len() * 3 / 4].to_vec();
    let mut rec = Recording::open(cut, &RecordingOptions::default()).expect("opens by scanning");
    assert!(
        rec.warnings().iter().any(|w| w.contains("no summary")),
        "{:?}",
        rec.warnings()
    );
    assert!(rec.len() >= 3 && rec.len() < 8, "{} frames", rec.len());
    let (_, _, color) = png(&fixture("reference/color/000000.png"));
    let f = rec.frame(0).expect("first frame still decodes");
    assert!(f
        .color
        .iter()
        .map(|&c| u16::from(c))
        .eq(color.iter().copied()));
}

#[test]
fn named_topic_that_is_missing_lists_the_topics_there_are() {
    let bytes = FileBytes::open(&fixture("ros_none.bag")).expect("fixture");
    let options = RecordingOptions {
        color_topic: Some("/camera/rgb".into()),
        ..RecordingOptions::default()
    };
    let e = Recording::open(bytes, &options).err().expect("refused");
    let text = e.to_string();
    assert!(
        text.contains("/camera/rgb") && text.contains("/camera/color/image_raw"),
        "{text}"
    );
}

#[test]
fn not_a_bag_is_refused_by_name() {
    let e = Recording::open(b"PK\x03\x04 a zip".to_vec(), &RecordingOptions::default())
        .err()
        .expect("refused");
    assert!(matches!(e, RecordingError::UnknownFormat { .. }), "{e}");
}
