//! The command line as a user meets it: help for every command, errors that
//! suggest, exit codes, progress only on a terminal, completions.

mod common;

use std::process::Command;

use common::run;

/// The commands `upetrack --help` lists (clap's own `help` left out).
fn commands() -> Vec<String> {
    let out = run(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let list = text
        .split("Commands:\n")
        .nth(1)
        .and_then(|t| t.split("\n\n").next())
        .expect("a command list");
    list.lines()
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// Runs the command and returns its exit code and standard error.
fn exit(args: &[&str]) -> (Option<i32>, String) {
    let out = run(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Options each command's help must name (a sample that catches a command
/// losing its options or another's).
const OPTIONS: [(&str, &[&str]); 12] = [
    (
        "track",
        &["--out", "--algorithm", "--params", "--dlo", "--align"],
    ),
    (
        "eval",
        &["--algorithm", "--per-frame", "--json", "--markdown"],
    ),
    ("score", &["--json", "--markdown", "<SEQUENCE>"]),
    (
        "compare",
        &[
            "--data", "--frames", "--only", "--random", "--count", "--update",
        ],
    ),
    (
        "synth",
        &[
            "--frames",
            "--seed",
            "--hd",
            "--variant",
            "--rope-prior",
            "--y4m",
        ],
    ),
    ("bench", &["--frames", "--repeat", "--algorithm"]),
    ("overlay", &["--depth", "<FRAME>", "<OUT>"]),
    ("info", &["--json", "--color-topic", "--depth-topic"]),
    ("export", &["--frames", "--dlo"]),
    ("scenarios", &["--help"]),
    ("algorithms", &["--help"]),
    ("completions", &["<SHELL>"]),
];

#[test]
fn every_command_has_help_naming_its_options_and_an_example() {
    let listed = commands();
    let described: Vec<&str> = OPTIONS.iter().map(|(c, _)| *c).collect();
    assert_eq!(listed, described, "every listed command is checked here");
    for (command, options) in OPTIONS {
        let out = run(&[command, "--help"]);
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{command} --help: {:?}", out.status);
        assert!(
            help.contains(&format!("Usage: upetrack {command}")),
            "{command}: {help}"
        );
        for option in options {
            assert!(help.contains(option), "{command} --help lacks {option}");
        }
        if !["scenarios", "algorithms"].contains(&command) {
            assert!(help.contains("Example"), "{command} --help has no example");
        }
    }
}

#[test]
fn version_is_the_packages() {
    let out = run(&["--version"]);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("upetrack {}", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn an_unknown_option_is_a_usage_error_with_a_suggestion() {
    let (code, err) = exit(&[
        "track",
        "samples/static-s",
        "--out",
        "x.json",
        "--algoritm",
        "cpd",
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("'--algoritm'") && err.contains("'--algorithm'"),
        "{err}"
    );

    let (code, err) = exit(&["trak"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("'track'"), "{err}");

    let (code, err) = exit(&["eval", "x", "--algorithm", "upetrak"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("upetrack, cpd, trackdlo, cdcpd2"), "{err}");
}

#[test]
fn options_that_do_not_go_together_are_usage_errors() {
    let dir = common::temp_dir("command-line", "usage");
    let dir = dir.to_str().expect("utf-8");
    for args in [
        vec!["synth", "random", dir, "--hd"],
        vec!["synth", "static-s", dir, "--count", "3"],
        vec!["compare", "--only", "no-such-scene"],
        vec!["compare", "--count", "3"],
        vec![
            "track",
            "samples/static-s",
            "--out",
            "x.json",
            "--dlo",
            "dlo.json",
        ],
    ] {
        let (code, err) = exit(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
    }
}

#[test]
fn bad_input_exits_with_1_naming_the_file() {
    let (code, err) = exit(&["track", "/no/such/sequence", "--out", "x.json"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("/no/such/sequence"), "{err}");
}

#[test]
fn the_algorithm_lists_are_the_cores() {
    let core: Vec<&str> = upetrack::Algorithm::ALL.iter().map(|a| a.name()).collect();
    let out = run(&["eval", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    let in_help: Vec<&str> = help
        .lines()
        .filter_map(|l| l.trim().strip_prefix("- "))
        .filter_map(|l| l.split(':').next())
        .filter(|name| !name.contains(' '))
        .take_while(|name| !["x86-sse"].contains(name))
        .collect();
    assert_eq!(in_help, core, "{help}");
    let out = run(&["algorithms"]);
    let listed: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect();
    assert_eq!(listed, core);
}

#[test]
fn completions_are_written_for_each_shell() {
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let out = run(&["completions", shell]);
        assert!(out.status.success(), "{shell}");
        let script = String::from_utf8_lossy(&out.stdout);
        for word in ["upetrack", "track", "per-frame"] {
            assert!(script.contains(word), "{shell} completion lacks {word}");
        }
    }
    assert_eq!(run(&["completions", "tcsh"]).status.code(), Some(2));
}

/// Runs `upetrack <args>` on a pseudo-terminal (util-linux `script`) and
/// returns what it printed there.
fn on_a_terminal(args: &str) -> String {
    let out = Command::new("script")
        .args([
            "-qec",
            &format!("{} {args}", env!("CARGO_BIN_EXE_upetrack")),
            "/dev/null",
        ])
        .output()
        .expect("util-linux `script` runs the command on a pseudo-terminal");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// What a progress bar prints: the count of frames and the rate.
const BAR: &str = "frames (";

#[test]
fn progress_is_drawn_on_a_terminal_only_and_never_with_quiet() {
    let dir = common::temp_dir("command-line", "progress");
    std::fs::create_dir_all(&dir).expect("folder");
    let out = dir.join("result.json");
    let out = out.to_str().expect("utf-8");
    let seq = concat!(env!("CARGO_MANIFEST_DIR"), "/../samples/static-s");
    let shown = on_a_terminal(&format!("track {seq} --out {out}"));
    assert!(shown.contains(BAR), "a terminal shows the bar: {shown}");
    let quiet = on_a_terminal(&format!("track {seq} --out {out} --quiet"));
    assert!(
        !quiet.contains(BAR) && quiet.contains("25 frames tracked"),
        "{quiet}"
    );
    let piped = run(&["track", seq, "--out", out]);
    let err = String::from_utf8_lossy(&piped.stderr);
    assert!(piped.status.success());
    assert!(!err.contains(BAR) && !err.contains('\r'), "{err}");
}

/// Drawn scene 5094 (of the fresh range) keeps contradicting its state
/// from frame 13 (the cloud unexplained by the nodes): it would be
/// re-initialised on every frame. Recoveries in a row back off (frames
/// 13, 15, 19), so the work a frame does no longer grows with how wrong
/// the state is. (Scene 1012 served until grey ranges allowed for colour
/// noise, 1015 until its rope was found round its tight bends, 1058 until
/// a loop's kinked ends were joined at frame 0.)
#[test]
fn a_state_that_keeps_contradicting_the_images_is_not_reinitialised_every_frame() {
    let dir = common::temp_dir("command-line", "backoff");
    let seq = dir.join("scene");
    let out = dir.join("result.json");
    let (seq, out) = (seq.to_str().expect("utf-8"), out.to_str().expect("utf-8"));
    let o = run(&["synth", "random", seq, "--seed", "5094", "--frames", "48"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&["track", seq, "--out", out]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let recovered = recovered_frames(out);
    assert!(
        !recovered.is_empty(),
        "the scene no longer contradicts its state"
    );
    assert!(recovered.len() <= 5, "recovered on frames {recovered:?}");
    // Every stepped frame says what the tests read and what came of it:
    // the frames between recoveries that still contradict say they waited.
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out).expect("result")).expect("json");
    let frames = result["frames"].as_array().expect("frames");
    assert!(
        frames[0].get("checks").is_none(),
        "the first frame initialised"
    );
    let verdict = |f: &serde_json::Value| f["checks"]["verdict"].as_str().map(String::from);
    let by_verdict = |v: &str| -> Vec<usize> {
        (0..frames.len())
            .filter(|&i| verdict(&frames[i]).as_deref() == Some(v))
            .collect()
    };
    assert_eq!(by_verdict("recovered"), recovered);
    assert!(!by_verdict("waited").is_empty(), "no frame waited");
    for (i, f) in frames.iter().enumerate().skip(1) {
        let fired = f["checks"]["fired"]
            .as_array()
            .expect("every stepped frame has checks");
        assert_eq!(
            fired.is_empty(),
            verdict(f).as_deref() == Some("agreed"),
            "frame {i}"
        );
        // What a search found is said where there was one and a rope in it.
        let searched_and_found = !matches!(
            verdict(f).as_deref(),
            Some("agreed" | "waited" | "nothing_found")
        );
        let found = &f["checks"]["found"];
        assert_eq!(found.is_object(), searched_and_found, "frame {i}: {found}");
        if searched_and_found {
            assert!(
                found["length"].as_f64().is_some_and(|l| l > 0.0),
                "frame {i}: {found}"
            );
            assert!(found["seen_left_out"].is_u64(), "frame {i}: {found}");
        }
    }
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(said.contains("a recovery test fired on"), "{said}");
}

/// The frames of `result.json` (written by `track`) reported recovered.
fn recovered_frames(out: &str) -> Vec<usize> {
    let result: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out).expect("result")).expect("json");
    result["frames"]
        .as_array()
        .expect("frames")
        .iter()
        .enumerate()
        .filter(|(_, f)| f["recovered"] == true)
        .map(|(i, _)| i)
        .collect()
}

/// Regression for "a long rope tracked with few nodes is re-initialised
/// again and again": drawn scene 1040 (a 1.39 m rope at rest, nothing
/// over it) tracked with 10 nodes, 15 cm apart. The unexplained cloud was
/// measured from the nodes, and half a spacing is beyond its 4 cm reach:
/// recovered on frames 1, 3, 7 and 15 of 16 (as often as the back-off
/// allowed). Measured from the axis through the nodes, never.
#[test]
fn a_long_rope_tracked_with_few_nodes_is_not_reinitialised() {
    let dir = common::temp_dir("command-line", "few-nodes");
    let (seq, out, params) = (dir.join("scene"), dir.join("r.json"), dir.join("p.json"));
    std::fs::create_dir_all(&dir).expect("folder");
    std::fs::write(&params, r#"{"node_count": 10}"#).expect("params");
    let [seq, out, params] = [&seq, &out, &params].map(|p| p.to_str().expect("utf-8"));
    let o = run(&["synth", "random", seq, "--seed", "1040", "--frames", "16"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&["track", seq, "--out", out, "--params", params]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(recovered_frames(out), Vec::<usize>::new());
}
