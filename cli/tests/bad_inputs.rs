//! The catalogue of bad inputs: every case is run through the real command
//! (or the tracker for frame-level cases) and must end in its documented
//! outcome: a non-zero exit with a message naming the file and the problem,
//! or a documented recovery. See docs/robustness.md.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use upetrack::math::Vec3;
use upetrack::tracker::FrameStatus;
use upetrack::{Frame, Params, Rect, Tracker};
use upetrack_synth::{RenderSettings, Scenario, ScenarioKind};

fn upetrack() -> Command {
    Command::new(env!("CARGO_BIN_EXE_upetrack"))
}

/// A valid 4-frame sequence, written once per test run.
fn base() -> &'static Path {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    BASE.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("upetrack-bad-base-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let out = upetrack()
            .args([
                "synth",
                "static-s",
                dir.to_str().expect("utf-8"),
                "--frames",
                "4",
                "--seed",
                "9",
            ])
            .output()
            .expect("synth");
        assert!(out.status.success());
        dir
    })
}

/// A fresh copy of the base sequence named after the case.
fn copy(case: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("upetrack-bad-{}-{case}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(base(), &dir);
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read_dir") {
        let e = e.expect("entry");
        let target = to.join(e.file_name());
        if e.file_type().expect("type").is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).expect("copy");
        }
    }
}

/// Runs `track` and returns (success, stderr).
fn track(seq: &Path, extra: &[&str]) -> (bool, String) {
    let out_file = seq.with_extension("result.json");
    let mut args = vec![
        "track",
        seq.to_str().expect("utf-8"),
        "--out",
        out_file.to_str().expect("utf-8"),
    ];
    args.extend_from_slice(extra);
    let out = upetrack().args(&args).output().expect("run");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Asserts a failure whose message contains every fragment.
fn fails_with(seq: &Path, extra: &[&str], fragments: &[&str]) {
    let (ok, err) = track(seq, extra);
    assert!(!ok, "{} should fail", seq.display());
    for f in fragments {
        assert!(err.contains(f), "message lacks `{f}`: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

fn png(
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, width, height);
        e.set_color(color);
        e.set_depth(depth);
        e.write_header()
            .expect("header")
            .write_image_data(data)
            .expect("data");
    }
    out
}

#[test]
fn truncated_and_corrupt_images_name_the_file() {
    let s = copy("trunc-jpeg");
    let f = s.join("color/000002.jpg");
    let b = std::fs::read(&f).expect("read");
    std::fs::write(&f, &b[..b.len() / 3]).expect("write");
    fails_with(&s, &[], &["000002.jpg"]);

    let s = copy("corrupt-png");
    let f = s.join("depth/000001.png");
    let mut b = std::fs::read(&f).expect("read");
    let mid = b.len() / 2;
    for x in &mut b[mid..mid + 64] {
        *x ^= 0x5A;
    }
    std::fs::write(&f, &b).expect("write");
    fails_with(&s, &[], &["000001.png"]);

    let s = copy("not-an-image");
    std::fs::write(s.join("color/000000.jpg"), b"hello").expect("write");
    fails_with(&s, &[], &["000000.jpg", "not a PNG or JPEG"]);
}

#[test]
fn depth_must_be_16_bit_single_channel() {
    let s = copy("depth-8bit");
    let data = vec![100u8; 640 * 480];
    std::fs::write(
        s.join("depth/000000.png"),
        png(
            640,
            480,
            png::ColorType::Grayscale,
            png::BitDepth::Eight,
            &data,
        ),
    )
    .expect("write");
    fails_with(&s, &[], &["000000.png", "16-bit single-channel"]);

    let s = copy("depth-rgb");
    let data = vec![100u8; 640 * 480 * 3];
    std::fs::write(
        s.join("depth/000000.png"),
        png(640, 480, png::ColorType::Rgb, png::BitDepth::Eight, &data),
    )
    .expect("write");
    fails_with(&s, &[], &["000000.png", "16-bit single-channel"]);
}

#[test]
fn images_of_the_wrong_size_are_refused() {
    let s = copy("size-mismatch");
    let data = vec![0u8; 320 * 240 * 2];
    std::fs::write(
        s.join("depth/000003.png"),
        png(
            320,
            240,
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &data,
        ),
    )
    .expect("write");
    fails_with(&s, &[], &["000003.png", "320x240", "640x480"]);
}

#[test]
fn intrinsics_problems_are_named() {
    let cases: [(&str, Option<&str>, &[&str]); 6] = [
        (
            "intr-missing",
            None,
            &["camera_intrinsic.json", "not found"],
        ),
        (
            "intr-malformed",
            Some("{\"width\": 640,"),
            &["camera_intrinsic.json", "invalid JSON"],
        ),
        (
            "intr-fx-zero",
            Some(r#"{"width":640,"height":480,"intrinsic_matrix":[0,0,0,0,615,0,320,240,1]}"#),
            &["fx", "positive"],
        ),
        (
            "intr-fy-negative",
            Some(r#"{"width":640,"height":480,"intrinsic_matrix":[615,0,0,0,-615,0,320,240,1]}"#),
            &["fy", "positive"],
        ),
        (
            "intr-short",
            Some(r#"{"width":640,"height":480,"intrinsic_matrix":[615,0,0]}"#),
            &["intrinsic_matrix has 3 values"],
        ),
        (
            "intr-size",
            Some(r#"{"width":320,"height":240,"intrinsic_matrix":[615,0,0,0,615,0,320,240,1]}"#),
            &["000000", "640x480", "320x240"],
        ),
    ];
    for (case, content, fragments) in cases {
        let s = copy(case);
        match content {
            None => std::fs::remove_file(s.join("camera_intrinsic.json")).expect("rm"),
            Some(c) => std::fs::write(s.join("camera_intrinsic.json"), c).expect("write"),
        }
        fails_with(&s, &[], fragments);
    }
}

#[test]
fn folder_problems_are_named() {
    let s = copy("count-mismatch");
    std::fs::remove_file(s.join("depth/000003.png")).expect("rm");
    fails_with(&s, &[], &["4 colour frames but 3 depth frames"]);

    let empty = std::env::temp_dir().join(format!("upetrack-bad-{}-empty", std::process::id()));
    let _ = std::fs::remove_dir_all(&empty);
    std::fs::create_dir_all(&empty).expect("mkdir");
    fails_with(&empty, &[], &["camera_intrinsic.json", "not found"]);

    let s = copy("no-frames");
    for d in ["color", "depth"] {
        for e in std::fs::read_dir(s.join(d)).expect("dir") {
            std::fs::remove_file(e.expect("e").path()).expect("rm");
        }
    }
    fails_with(&s, &[], &["no .jpg or .png frames"]);

    // A file that is not an input is named for what it is.
    let file = s.join("dlo.json");
    fails_with(&file, &[], &["a JSON file", "not a sequence folder"]);
    let empty_file = s.join("empty.bag");
    std::fs::write(&empty_file, b"").expect("write");
    fails_with(&empty_file, &[], &["an empty file"]);
    let jpeg = s.join("photo.bag");
    std::fs::write(&jpeg, [0xff, 0xd8, 0xff, 0xe0, 0, 0x10]).expect("write");
    fails_with(&jpeg, &[], &["a JPEG image"]);
}

#[test]
fn zip_problems_are_refused() {
    let s = copy("zip-src");
    let zip = s.with_extension("zip");
    let out = Command::new("python3")
        .args(["-c", "import sys, zipfile\nz = zipfile.ZipFile(sys.argv[1], 'w')\nz.writestr('../escape/camera_intrinsic.json', '{}')\nz.close()", zip.to_str().expect("utf-8")])
        .output()
        .expect("python3");
    assert!(out.status.success());
    fails_with(&zip, &[], &["outside the archive"]);

    let bomb = s.with_extension("bomb.zip");
    let out = Command::new("python3")
        .args(["-c", "import sys, zipfile\nz = zipfile.ZipFile(sys.argv[1], 'w', zipfile.ZIP_DEFLATED)\nz.writestr('depth/000000.png', bytes(50_000_000))\nz.close()", bomb.to_str().expect("utf-8")])
        .output()
        .expect("python3");
    assert!(out.status.success());
    fails_with(&bomb, &[], &["zip bomb"]);

    // A good zip of the sequence tracks.
    let good = s.with_extension("good.zip");
    let out = Command::new("python3")
        .args(["-c", "import shutil, sys\nshutil.make_archive(sys.argv[1][:-4], 'zip', sys.argv[2], sys.argv[3])", good.to_str().expect("utf-8"), s.parent().expect("parent").to_str().expect("utf-8"), s.file_name().expect("name").to_str().expect("utf-8")])
        .output()
        .expect("python3");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (ok, err) = track(&good, &[]);
    assert!(ok, "{err}");
}

#[test]
fn dlo_json_problems_are_named_and_outside_rectangles_are_clipped() {
    let cases: [(&str, &str, &[&str]); 9] = [
        (
            "dlo-depth-scale",
            r#"{"depth_scale": -0.001}"#,
            &[
                "dlo.json",
                "depth_scale -0.001 must be finite and in (0, 1)",
            ],
        ),
        (
            "dlo-fps",
            r#"{"fps": 0}"#,
            &["dlo.json", "fps 0 must be in (0, 10000]"],
        ),
        (
            "dlo-gt-absolute",
            r#"{"groundtruth": "/etc/hostname"}"#,
            &["dlo.json", "inside the sequence folder"],
        ),
        (
            "dlo-gt-parent",
            r#"{"groundtruth": "../groundtruth.json"}"#,
            &["dlo.json", "inside the sequence folder"],
        ),
        (
            "dlo-hsv-300",
            r#"{"segmentation": {"hsv_lower": [90, 90, 30], "hsv_upper": [130, 300, 255]}}"#,
            &["dlo.json", "invalid value: integer `300`, expected u8"],
        ),
        (
            "dlo-types",
            r#"{"segmentation": {"hsv_lower": "blue", "hsv_upper": [130, 255, 255]}}"#,
            &["dlo.json", "invalid JSON"],
        ),
        (
            "dlo-inverted",
            r#"{"segmentation": {"hsv_lower": [90, 200, 30], "hsv_upper": [130, 100, 255]}}"#,
            &["dlo.json", "saturation range is inverted"],
        ),
        (
            "dlo-hue",
            r#"{"segmentation": {"hsv_lower": [90, 90, 30], "hsv_upper": [200, 255, 255]}}"#,
            &["dlo.json", "hue bound 200"],
        ),
        (
            "dlo-negative-rect",
            r#"{"occlusions": [{"frames": [0, 3], "rect": [10, 10, -5, 20]}]}"#,
            &["dlo.json", "negative width"],
        ),
    ];
    for (case, content, fragments) in cases {
        let s = copy(case);
        std::fs::write(s.join("dlo.json"), content).expect("write");
        fails_with(&s, &[], fragments);
    }
    // A rectangle reaching outside the image is clipped (documented recovery).
    let s = copy("dlo-outside");
    let cfg = std::fs::read_to_string(s.join("dlo.json")).expect("read");
    let mut v: serde_json::Value = serde_json::from_str(&cfg).expect("json");
    v["occlusions"] = serde_json::json!([{ "frames": [0, 3], "rect": [-100, -100, 50, 50] }, { "frames": [1, 2], "rect": [600, 400, 1000, 1000] }]);
    std::fs::write(s.join("dlo.json"), v.to_string()).expect("write");
    let (ok, err) = track(&s, &[]);
    assert!(ok, "{err}");
}

/// Regression: a folder of symbolic links to frames was read as a folder
/// without frames ("no .jpg or .png frames").
#[test]
fn symlinked_frames_are_frames() {
    let s = copy("symlinks");
    for dir in ["color", "depth"] {
        let real = s.join(format!("{dir}-real"));
        std::fs::rename(s.join(dir), &real).expect("rename");
        std::fs::create_dir(s.join(dir)).expect("mkdir");
        for e in std::fs::read_dir(&real).expect("read_dir") {
            let e = e.expect("entry");
            std::os::unix::fs::symlink(e.path(), s.join(dir).join(e.file_name())).expect("symlink");
        }
    }
    let (ok, err) = track(&s, &[]);
    assert!(ok, "{err}");
}

#[test]
fn bad_parameters_are_named() {
    let s = copy("params");
    let cases: [(&str, &[&str]); 8] = [
        (r#"{"node_count": 3}"#, &["node_count"]),
        (r#"{"node_count": 5000000}"#, &["node_count"]),
        (r#"{"visibility_radius": -0.02}"#, &["visibility_radius"]),
        (r#"{"displacement_decay": 1e999}"#, &["params.json"]),
        (r#"{"bending_resistance": "stiff"}"#, &["params.json"]),
        (r#"{"no_such_parameter": 1}"#, &["no_such_parameter"]),
        (
            r#"{"reinit_visible_fraction": -5}"#,
            &["reinit_visible_fraction", "in [0, 1]"],
        ),
        (
            r#"{"reinit_visible_fraction": 1e300}"#,
            &["reinit_visible_fraction"],
        ),
    ];
    for (content, fragments) in cases {
        let p = s.join("params.json");
        std::fs::write(&p, content).expect("write");
        fails_with(&s, &["--params", p.to_str().expect("utf-8")], fragments);
    }
}

#[test]
fn frames_without_rope_or_depth_are_reported_lost_and_every_frame_is_written() {
    let s = copy("no-rope");
    // Without the sample's occlusion, so that frame 3 shows the whole rope.
    std::fs::write(s.join("dlo.json"), "{}").expect("write");
    // Blank colour in frame 1 (white JPEG): no rope pixels.
    let white =
        upetrack_io::write::encode_jpeg(640, 480, &vec![255u8; 640 * 480 * 3], 90).expect("jpeg");
    std::fs::write(s.join("color/000001.jpg"), white).expect("write");
    // All depth zero in frame 2.
    let zeros =
        upetrack_io::write::encode_depth_png(640, 480, &vec![0u16; 640 * 480]).expect("png");
    std::fs::write(s.join("depth/000002.png"), zeros).expect("write");
    let (ok, err) = track(&s, &[]);
    assert!(ok, "{err}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(s.with_extension("result.json")).expect("result"))
            .expect("json");
    let frames = v["frames"].as_array().expect("frames");
    assert_eq!(frames.len(), 4);
    assert_eq!(frames[1]["lost"], true, "{}", frames[1]);
    assert!(frames[1]["reason"]
        .as_str()
        .expect("reason")
        .contains("visible"));
    assert_eq!(frames[2]["lost"], true, "{}", frames[2]);
    assert!(
        frames[3].get("lost").is_none(),
        "frame 3 tracks again: {}",
        frames[3]
    );
}

/// Frames of a scenario with the rope moved by `shift` (camera frame, metres).
fn frames_of(
    kind: ScenarioKind,
    n: usize,
    seed: u64,
    shift: Vec3,
) -> (Scenario, Vec<upetrack_synth::SynthFrame>) {
    let mut s = Scenario::new(kind, n, seed, RenderSettings::default());
    // Camera frame x right, y down -> world x, -y.
    for p in s.rope.x.iter_mut() {
        p.x += shift.x;
        p.y -= shift.y;
    }
    let mut frames = Vec::new();
    while let Some(f) = s.next_frame() {
        frames.push(f);
    }
    (s, frames)
}

#[test]
fn rope_hidden_for_100_frames_then_back_elsewhere_is_reacquired() {
    let (s, first) = frames_of(ScenarioKind::StaticS, 3, 5, Vec3::zeros());
    let (_, later) = frames_of(ScenarioKind::StaticS, 3, 6, Vec3::new(0.04, 0.03, 0.0));
    let mut tracker = Tracker::new(Params::default(), s.camera(), s.hsv()).expect("tracker");
    let all = Rect {
        x: 0,
        y: 0,
        w: 640,
        h: 480,
    };
    let run = |t: &mut Tracker, f: &upetrack_synth::SynthFrame, rects: &[Rect]| {
        let frame = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
        t.process(&frame, rects).expect("process")
    };
    for f in &first {
        assert!(!run(&mut tracker, f, &[]).is_lost());
    }
    let held = tracker.nodes().to_vec();
    for _ in 0..100 {
        let out = run(&mut tracker, &first[2], &[all]);
        assert!(out.is_lost(), "{:?}", out.status);
        assert_eq!(out.nodes, held, "state held while lost");
    }
    let back = run(&mut tracker, &later[0], &[]);
    assert_eq!(back.status, FrameStatus::Initialised, "{:?}", back.status);
    let e = upetrack::metrics::frame_error(&back.nodes, &later[0].groundtruth).expect("error");
    assert!(e < 0.006, "re-acquired {e} m from the rope");
    let next = run(&mut tracker, &later[1], &[]);
    assert_eq!(next.status, FrameStatus::Tracked);
}

#[test]
fn sudden_jump_is_reinitialised_and_a_bad_frame_does_not_break_the_state() {
    let (s, a) = frames_of(ScenarioKind::StaticS, 2, 7, Vec3::zeros());
    let (_, b) = frames_of(ScenarioKind::StaticS, 2, 7, Vec3::new(0.10, 0.06, 0.0));
    let mut tracker = Tracker::new(Params::default(), s.camera(), s.hsv()).expect("tracker");
    let run = |t: &mut Tracker, f: &upetrack_synth::SynthFrame| {
        let frame = Frame::new(640, 480, &f.rgb, &f.depth, 0.001).expect("frame");
        t.process(&frame, &[]).expect("process")
    };
    run(&mut tracker, &a[0]);
    assert_eq!(run(&mut tracker, &a[1]).status, FrameStatus::Tracked);
    // A frame of the wrong size is an error; the state is untouched.
    let before = tracker.snapshot();
    let small = Frame::new(2, 2, &[0; 12], &[0; 4], 0.001).expect("frame");
    assert!(matches!(
        tracker.process(&small, &[]),
        Err(upetrack::tracker::TrackerError::Frame(_))
    ));
    assert_eq!(tracker.snapshot(), before);
    // The rope jumps 10 cm: no node sees it any more, so it is found again at once.
    let out = run(&mut tracker, &b[0]);
    assert_eq!(out.status, FrameStatus::Initialised, "{:?}", out.status);
    let e = upetrack::metrics::frame_error(&out.nodes, &b[0].groundtruth).expect("error");
    assert!(e < 0.006, "after the jump {e} m");
    assert_eq!(run(&mut tracker, &b[1]).status, FrameStatus::Tracked);
}
