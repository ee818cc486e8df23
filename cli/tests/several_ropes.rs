//! Several ropes at once: the simulator's scenes of several ropes written
//! by `upetrack synth` (dlo.json lists the ropes, each with its ground
//! truth), tracked and scored per rope by `upetrack eval`, against the
//! same ropes tracked alone.

mod common;

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use common::{run, run_ok, temp_dir};
use serde_json::Value;

/// Frames of every scene here: the pulls run from 30 % to 85 % of them.
const FRAMES: &str = "45";

/// `upetrack synth <scene> <dir> --frames 45 <extra>`, once per process.
fn scene(name: &str, extra: &[&str]) -> PathBuf {
    static MADE: OnceLock<std::sync::Mutex<Vec<PathBuf>>> = OnceLock::new();
    let label = format!("{name}{}", extra.join("")).replace(['-', ' '], "_");
    let dir = std::env::temp_dir().join(format!("upetrack-several-{}-{label}", std::process::id()));
    let made = MADE.get_or_init(Default::default);
    let mut made = made.lock().unwrap_or_else(|e| e.into_inner());
    if !made.contains(&dir) {
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.to_str().expect("utf-8");
        let mut args = vec!["synth", name, path, "--frames", FRAMES];
        args.extend_from_slice(extra);
        run_ok(&args);
        made.push(dir.clone());
    }
    dir
}

/// `upetrack eval <dir> [--algorithm A]`: its rows, by sequence name, and
/// its printed table.
fn eval(dir: &Path, algorithm: &str) -> (Vec<Value>, String) {
    let json = dir.with_extension(format!("{algorithm}.json"));
    let out = run_ok(&[
        "eval",
        dir.to_str().expect("utf-8"),
        "--algorithm",
        algorithm,
        "--json",
        json.to_str().expect("utf-8"),
    ]);
    let rows: Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("rows")).expect("json");
    (
        rows.as_array().expect("rows").clone(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

/// The row of `rows` whose sequence ends with `suffix`.
fn row<'a>(rows: &'a [Value], suffix: &str) -> &'a Value {
    rows.iter()
        .find(|r| r["sequence"].as_str().is_some_and(|s| s.ends_with(suffix)))
        .unwrap_or_else(|| panic!("no row {suffix} in {rows:?}"))
}

fn number(row: &Value, key: &str) -> f64 {
    row[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {row}"))
}

/// The mean error (mm) of a row.
fn mean_mm(row: &Value) -> f64 {
    row["mm"]["mean"]
        .as_f64()
        .unwrap_or_else(|| panic!("mean in {row}"))
}

/// Each rope of `name`'s scene tracked beside the others, against the same
/// scene made with that rope alone: `(rope, together, alone)`, mean mm.
fn beside_and_alone(name: &str, ropes: &[&str], rows: &[Value]) -> Vec<(String, f64, f64)> {
    ropes
        .iter()
        .enumerate()
        .map(|(k, rope)| {
            let alone = scene(name, &["--only", &k.to_string()]);
            let (single, _) = eval(&alone, "upetrack");
            (
                rope.to_string(),
                mean_mm(row(rows, rope)),
                mean_mm(&single[0]),
            )
        })
        .collect()
}

/// The scene `name` of two blue ropes: no identity swap, no frame above
/// 20 mm, each rope under 1.5x its error alone (the bound); the
/// rows and table of its evaluation.
fn two_ropes_of_one_colour_hold(name: &str) -> (Vec<Value>, String) {
    let both = scene(name, &[]);
    let (rows, table) = eval(&both, "upetrack");
    let all = row(&rows, "/all");
    assert_eq!(all["identity_swaps"], 0, "{table}");
    assert!(number(all, "max_mm") < 20.0, "{table}");
    for (rope, together, alone) in beside_and_alone(name, &["blue-a", "blue-b"], &rows) {
        assert!(
            together < 1.5 * alone,
            "{rope}: {together:.2} mm beside the other rope, {alone:.2} alone\n{table}"
        );
    }
    (rows, table)
}

#[test]
fn two_ropes_of_one_colour_keep_their_identities_while_one_is_dragged_across_the_other() {
    // Measured 1.20x and 1.21x the rope alone (90 frames). One tracker per
    // rope given both ropes' pixels (no sharing) is off by 28-34 mm.
    let (rows, table) = two_ropes_of_one_colour_hold("two-ropes-crossing");
    assert_eq!(row(&rows, "/all")["swapped_frames"], 0, "{table}");
}

#[test]
fn a_rope_pulled_out_from_under_another_of_its_colour_stays_itself() {
    two_ropes_of_one_colour_hold("rope-from-under");
}

#[test]
fn a_rope_that_leaves_the_view_and_comes_back_is_found_again_as_itself() {
    let dir = scene("rope-leaves-view", &[]);
    let (rows, table) = eval(&dir, "upetrack");
    let all = row(&rows, "/all");
    assert_eq!(all["identity_swaps"], 0, "{table}");
    assert_eq!(all["swapped_frames"], 0, "{table}");
    // It did leave: lost while out of the image (13 of 45 frames).
    let gone = row(&rows, "/blue-b");
    assert!(number(gone, "lost_frames") >= 5.0, "{table}");
    // The other stayed tracked throughout, and the one back is itself on
    // the last frames (the command's per-frame errors).
    let stayed = row(&rows, "/blue-a");
    assert!(
        number(stayed, "lost_frames") == 0.0 && number(stayed, "max_mm") < 5.0,
        "{table}"
    );
    let csv = dir.with_extension("frames.csv");
    run_ok(&[
        "eval",
        dir.to_str().expect("utf-8"),
        "--per-frame",
        csv.to_str().expect("utf-8"),
    ]);
    let text = std::fs::read_to_string(&csv).expect("csv");
    let back: Vec<(f64, bool)> = text
        .lines()
        .filter(|l| l.contains("/blue-b,"))
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[2].parse::<f64>().unwrap_or(f64::NAN), c[7] == "true")
        })
        .collect();
    let last = &back[back.len() - 5..];
    assert!(
        last.iter().all(|(mm, lost)| !lost && *mm < 3.0),
        "{last:?}\n{table}"
    );
}

/// A copy of `dir` (frames linked) whose dlo.json keeps only rope `k` of
/// its `ropes`: that rope tracked alone in the same images.
fn with_one_rope(dir: &Path, k: usize, name: &str) -> PathBuf {
    let copy = temp_dir("several-one", name);
    std::fs::create_dir_all(&copy).expect("folder");
    for entry in std::fs::read_dir(dir).expect("list") {
        let entry = entry.expect("entry");
        let to = copy.join(entry.file_name());
        if entry.path().is_dir() {
            std::fs::create_dir_all(&to).expect("folder");
            for f in std::fs::read_dir(entry.path()).expect("list") {
                let f = f.expect("file");
                std::fs::hard_link(f.path(), to.join(f.file_name()))
                    .or_else(|_| std::fs::copy(f.path(), to.join(f.file_name())).map(|_| ()))
                    .expect("link");
            }
        } else {
            std::fs::copy(entry.path(), &to).expect("copy");
        }
    }
    let path = copy.join("dlo.json");
    let mut dlo: Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("dlo")).expect("json");
    let rope = dlo["ropes"][k].clone();
    dlo["ropes"] = Value::Array(vec![rope.clone()]);
    dlo["segmentation"] = rope["segmentation"].clone();
    dlo["groundtruth"] = rope["groundtruth"].clone();
    std::fs::write(&path, dlo.to_string()).expect("write");
    copy
}

#[test]
fn three_ropes_of_three_colours_under_a_box_are_each_tracked_as_well_as_alone() {
    let all_three = scene("three-ropes", &[]);
    let (rows, table) = eval(&all_three, "upetrack");
    assert_eq!(row(&rows, "/all")["identity_swaps"], 0, "{table}");
    // Each rope against itself tracked alone in the same images (the issue
    // allows 1.2x; measured 1.00x: other colours' pixels are never shared).
    for (k, rope) in ["red", "blue", "green"].iter().enumerate() {
        let alone = with_one_rope(&all_three, k, rope);
        let (single, _) = eval(&alone, "upetrack");
        let (together, by_itself) = (mean_mm(row(&rows, rope)), mean_mm(&single[0]));
        assert!(
            together <= 1.2 * by_itself,
            "{rope}: {together:.2} mm among three, {by_itself:.2} alone\n{table}"
        );
    }
}

#[test]
fn one_rope_listed_in_dlo_ropes_is_tracked_to_the_last_bit_as_without_the_list() {
    let dir = scene("static-s", &[]);
    let listed = temp_dir("several-listed", "static-s");
    std::fs::create_dir_all(&listed).expect("folder");
    let plain = dir.join("plain.json");
    run_ok(&[
        "track",
        dir.to_str().expect("utf-8"),
        "-o",
        plain.to_str().expect("utf-8"),
    ]);
    // The same folder with its one rope in `ropes`.
    let mut dlo: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("dlo.json")).expect("dlo"))
            .expect("json");
    dlo["ropes"] = serde_json::json!([{ "name": "the-rope", "segmentation": dlo["segmentation"] }]);
    std::fs::write(dir.join("dlo.json"), dlo.to_string()).expect("write");
    let as_list = dir.join("listed.json");
    run_ok(&[
        "track",
        dir.to_str().expect("utf-8"),
        "-o",
        as_list.to_str().expect("utf-8"),
    ]);
    let read = |p: &Path| -> Value {
        serde_json::from_str(&std::fs::read_to_string(p).expect("result")).expect("json")
    };
    let (a, b) = (read(&plain), read(&as_list));
    assert!(b.get("ropes").is_none(), "one rope writes no `ropes`");
    for (fa, fb) in a["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .zip(b["frames"].as_array().expect("frames"))
    {
        assert_eq!(fa["nodes"], fb["nodes"]);
        assert_eq!(fa["visible"], fb["visible"]);
    }
}

#[test]
fn a_result_of_several_ropes_lists_each_ropes_frames_the_first_also_as_frames() {
    let both = scene("two-ropes-crossing", &[]);
    let out_path = both.with_extension("result.json");
    run_ok(&[
        "track",
        both.to_str().expect("utf-8"),
        "-o",
        out_path.to_str().expect("utf-8"),
    ]);
    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(&out_path).expect("result")).expect("json");
    let ropes = result["ropes"].as_array().expect("ropes");
    assert_eq!(ropes.len(), 2);
    assert_eq!(ropes[0]["name"], "blue-a");
    assert_eq!(ropes[1]["name"], "blue-b");
    assert_eq!(ropes[0]["frames"], result["frames"]);
    let frames = FRAMES.parse::<usize>().expect("count");
    for rope in ropes {
        assert_eq!(rope["frames"].as_array().expect("frames").len(), frames);
    }
    // Scored again from the file, per rope.
    let score = run_ok(&[
        "score",
        both.to_str().expect("utf-8"),
        out_path.to_str().expect("utf-8"),
    ]);
    let table = String::from_utf8_lossy(&score.stdout);
    assert!(
        table.contains("/blue-b") && table.contains("identity swap"),
        "{table}"
    );
}

#[test]
fn a_dlo_json_of_too_many_or_ill_named_ropes_is_refused_with_the_reason() {
    let dir = scene("two-ropes-crossing", &[]);
    let bad = temp_dir("several-bad", "ropes");
    std::fs::create_dir_all(&bad).expect("folder");
    std::fs::create_dir_all(bad.join("color")).expect("folder");
    std::fs::create_dir_all(bad.join("depth")).expect("folder");
    for f in [
        "camera_intrinsic.json",
        "color/000000.jpg",
        "depth/000000.png",
    ] {
        std::fs::copy(dir.join(f), bad.join(f)).expect("copy");
    }
    let cases = [
        (
            serde_json::json!({ "ropes": vec![serde_json::json!({}); 9] }),
            "cap of 8",
        ),
        (
            serde_json::json!({ "ropes": [{ "name": "a" }, { "name": "a" }] }),
            "taken by an earlier rope",
        ),
        (
            serde_json::json!({ "ropes": [{}, { "segmentation": { "hsv_lower": [10, 0, 0], "hsv_upper": [200, 255, 255] } }] }),
            "ropes[1]: segmentation",
        ),
        (
            serde_json::json!({ "ropes": [{}, { "groundtruth": "../x.json" }] }),
            "ropes[1]: groundtruth",
        ),
    ];
    for (dlo, reason) in cases {
        std::fs::write(bad.join("dlo.json"), dlo.to_string()).expect("write");
        let out = run(&["track", bad.to_str().expect("utf-8"), "-o", "/dev/null"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(reason),
            "{reason}: {stderr}"
        );
    }
    let out = run(&[
        "synth",
        "three-ropes",
        bad.join("x").to_str().expect("utf-8"),
        "--without",
        "3",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("ropes 0 to 2"),
        "{stderr}"
    );
}
