//! The caps on lists read from a sequence's JSON files are enforced while
//! the file is read: the entry past a cap stops the parser (each test ends
//! its list with a broken tail, which a parser reading everything first
//! would report instead).

use upetrack_io::sequence::{
    DloConfig, GroundTruthFile, MAX_FRAMES, MAX_GROUNDTRUTH_POINTS, MAX_OCCLUSIONS,
};

fn list_of(item: &str, n: usize) -> String {
    vec![item; n].join(",")
}

#[test]
fn occlusions_past_the_cap_stop_the_parser() {
    let rect = r#"{"frames": [0, 1], "rect": [0, 0, 1, 1]}"#;
    let json = format!(
        r#"{{"occlusions": [{}, broken"#,
        list_of(rect, MAX_OCCLUSIONS + 1)
    );
    let e = DloConfig::parse(json.as_bytes(), "dlo.json").expect_err("refused");
    assert!(
        e.to_string().contains(&format!("cap of {MAX_OCCLUSIONS}")),
        "{e}"
    );
    // At the cap the list is read.
    let json = format!(r#"{{"occlusions": [{}]}}"#, list_of(rect, MAX_OCCLUSIONS));
    assert!(DloConfig::parse(json.as_bytes(), "dlo.json").is_ok());
}

#[test]
fn ground_truth_points_past_the_cap_stop_the_parser() {
    let json = format!(
        r#"{{"frames": [{{"frame": 0, "points": [{}, broken"#,
        list_of("[0,0,1]", MAX_GROUNDTRUTH_POINTS + 1)
    );
    let e = serde_json::from_str::<GroundTruthFile>(&json).expect_err("refused");
    assert!(
        e.to_string()
            .contains(&format!("cap of {MAX_GROUNDTRUTH_POINTS}")),
        "{e}"
    );
}

#[test]
fn ground_truth_frames_past_the_cap_stop_the_parser() {
    let json = format!(
        r#"{{"frames": [{}, broken"#,
        list_of(r#"{"frame": 0, "points": []}"#, MAX_FRAMES + 1)
    );
    let e = serde_json::from_str::<GroundTruthFile>(&json).expect_err("refused");
    assert!(
        e.to_string().contains(&format!("cap of {MAX_FRAMES}")),
        "{e}"
    );
}
