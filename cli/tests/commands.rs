//! The command's own tools on synthetic sequences: `synth`'s encoding
//! options and `score` on result files of any tracker.

use std::path::PathBuf;

use upetrack_io::{FolderSource, Sequence};

mod common;
use common::{run, synth};

fn temp_dir(name: &str) -> PathBuf {
    common::temp_dir("cmd", name)
}

/// The bundled opening sample's options: `--depth-noise 0` removes the
/// disparity noise (the flat table's depth spread collapses), `--jpeg-quality`
/// makes smaller colour files, and values out of range are refused.
#[test]
fn synth_depth_noise_and_jpeg_quality_take_effect_and_are_checked() {
    let write = |name: &str, extra: &[&str]| {
        let dir = temp_dir(name);
        let mut args = vec![
            "synth",
            "static-s",
            dir.to_str().expect("utf-8"),
            "--frames",
            "1",
        ];
        args.extend_from_slice(extra);
        let out = run(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        dir
    };
    // Spread of the depth over the image's top-left corner (table only).
    let spread = |dir: &PathBuf| {
        let seq = Sequence::open(FolderSource::new(dir)).expect("opens");
        let f = seq.frame(0).expect("decodes");
        let w = f.width as usize;
        let vals: Vec<f64> = (0..60)
            .flat_map(|v| (0..80).map(move |u| v * w + u))
            .map(|k| f.depth[k])
            .filter(|&d| d > 0)
            .map(f64::from)
            .collect();
        let mean = vals.iter().sum::<f64>() / vals.len() as f64;
        (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / vals.len() as f64).sqrt()
    };
    let noisy = write("noise-default", &[]);
    let quiet = write("noise-off", &["--depth-noise", "0", "--jpeg-quality", "60"]);
    let (a, b) = (spread(&noisy), spread(&quiet));
    assert!(
        a > 0.7 && b < 0.3,
        "depth spread {a} mm with noise, {b} mm without"
    );
    let size = |dir: &PathBuf| {
        std::fs::metadata(dir.join("color/000000.jpg"))
            .expect("jpg")
            .len()
    };
    assert!(
        size(&quiet) < size(&noisy) * 3 / 4,
        "{} vs {} bytes",
        size(&quiet),
        size(&noisy)
    );
    for bad in [
        ["--depth-noise", "NaN"],
        ["--depth-noise", "-1"],
        ["--jpeg-quality", "0"],
        ["--jpeg-quality", "101"],
    ] {
        let dir = temp_dir("bad-synth-option");
        let out = run(&[
            "synth",
            "static-s",
            dir.to_str().expect("utf-8"),
            "--frames",
            "1",
            bad[0],
            bad[1],
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(&bad[0][2..]),
            "{bad:?}: {err}"
        );
    }
}

/// `upetrack score` tables a result file written by any tracker as `eval`
/// tables the command's own run, and refuses one that does not fit the
/// sequence (a frame missing, a node that is not a number).
#[test]
fn score_tables_a_result_file_as_eval_does_and_refuses_one_that_does_not_fit() {
    let dir = temp_dir("score");
    synth("dynamic-pull", 12, &dir);
    let seq = dir.to_string_lossy().to_string();
    let out = dir.join("result.json");
    let o = run(&["track", &seq, "--out", &out.to_string_lossy()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let row = |text: &str| {
        text.lines()
            .find(|l| l.contains("| upetrack |"))
            .map(|l| l.split('|').skip(3).take(13).collect::<Vec<_>>().join("|"))
            .unwrap_or_default()
    };
    let eval = run(&["eval", &seq]);
    let score = run(&["score", &seq, &out.to_string_lossy()]);
    assert!(
        score.status.success(),
        "{}",
        String::from_utf8_lossy(&score.stderr)
    );
    let (e, s) = (
        String::from_utf8_lossy(&eval.stdout),
        String::from_utf8_lossy(&score.stdout),
    );
    assert!(
        !row(&e).is_empty() && row(&e) == row(&s),
        "eval:\n{e}\nscore:\n{s}"
    );
    // Another tracker's file: `params` empty, a frame dropped, a NaN node.
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("result")).expect("json");
    v["params"] = serde_json::json!({});
    v["algorithm"] = serde_json::json!("theirs");
    let foreign = dir.join("theirs.json");
    std::fs::write(&foreign, v.to_string()).expect("write");
    let o = run(&["score", &seq, &foreign.to_string_lossy()]);
    assert!(o.status.success() && String::from_utf8_lossy(&o.stdout).contains("| theirs |"));
    let mut short = v.clone();
    short["frames"].as_array_mut().expect("frames").pop();
    std::fs::write(&foreign, short.to_string()).expect("write");
    let o = run(&["score", &seq, &foreign.to_string_lossy()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("frames must be 0..12"),
        "{err}"
    );
    let mut nan = v.clone();
    nan["frames"][3]["nodes"][0][0] = serde_json::json!("NaN");
    std::fs::write(&foreign, nan.to_string().replace("\"NaN\"", "1e999")).expect("write");
    let o = run(&["score", &seq, &foreign.to_string_lossy()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("theirs.json"), "{err}");
}

/// Regression: `synth random --count` wrote its scenes without the
/// fingerprint `compare --random` keeps, so a range written ahead (an
/// hour for 100 long scenes) was written again, scene by scene, by the
/// first comparison on it. Now the comparison reads them, and the batch
/// run again keeps what is written; a batch with the rope's prior is no
/// comparison's cache.
#[test]
fn compare_random_reads_the_scenes_synth_random_wrote() {
    let data = temp_dir("random-ahead");
    let dir = data.to_str().expect("utf-8");
    let synth = [
        "synth", "random", dir, "--seed", "1000", "--count", "1", "--frames", "10",
    ];
    let out = run(&synth);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let again = run(&synth);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(again.status.success() && !err.contains("writing"), "{err}");
    let out = run(&[
        "compare", "--random", "tune", "--count", "1", "--frames", "10", "--data", dir, "-a",
        "upetrack", "-q",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("writing"), "{err}");
    // Written again with the rope's prior in `dlo.json`, the folder is no
    // longer the comparison's.
    let mut prior = synth.to_vec();
    prior.push("--rope-prior");
    assert!(run(&prior).status.success());
    let fingerprint = data.join("random-1000-10f/synth-fingerprint.txt");
    assert!(!fingerprint.exists());
}

/// `synth random` writes the drawn scene beside the contract's files (the
/// same draw for the same seed), `--count` writes one folder per seed,
/// options that the draw decides are refused, and `compare --random` names
/// the seed ranges when given another.
#[test]
fn synth_random_writes_its_draw_and_compare_random_checks_its_range() {
    let one = temp_dir("random-one");
    let two = temp_dir("random-two");
    for dir in [&one, &two] {
        let out = run(&[
            "synth",
            "random",
            dir.to_str().expect("utf-8"),
            "--seed",
            "2004",
            "--frames",
            "2",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let scene =
        |dir: &PathBuf| std::fs::read_to_string(dir.join("scene.json")).expect("scene.json");
    assert_eq!(scene(&one), scene(&two));
    let draw: serde_json::Value = serde_json::from_str(&scene(&one)).expect("json");
    assert_eq!(draw["seed"], 2004);
    assert!(draw["rope"]["length_m"]
        .as_f64()
        .is_some_and(|l| (0.3..=1.5).contains(&l)));
    let seq = Sequence::open(FolderSource::new(&one)).expect("opens");
    assert_eq!(seq.groundtruth.len(), 2);
    assert_eq!(
        seq.camera.width,
        draw["camera"]["width"].as_u64().expect("width") as u32
    );

    let batch = temp_dir("random-batch");
    let out = run(&[
        "synth",
        "random",
        batch.to_str().expect("utf-8"),
        "--seed",
        "5",
        "--count",
        "2",
        "--frames",
        "1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for seed in [5, 6] {
        assert!(batch.join(format!("random-{seed}-1f/scene.json")).is_file());
    }
    assert!(!batch.join("random-7-1f").exists());

    let refused = run(&["synth", "random", batch.to_str().expect("utf-8"), "--hd"]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("drawn from the seed"));
    let bad = run(&["compare", "--random", "everything", "--count", "1"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("tune") && err.contains("report"), "{err}");
}
