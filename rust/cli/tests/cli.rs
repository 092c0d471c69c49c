//! The `sixaxis` binary as a user runs it: JSON contracts and exit codes
//! (docs/SCENARIOS.md "JSON outputs of the CLI"),
//! errors on stderr without panics, atomic `--out`.

use std::process::{Command, Output};

use serde_json::Value;

fn sixaxis(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sixaxis"))
        .args(args)
        .output()
        .expect("the binary runs")
}

fn ok_json(args: &[&str]) -> Value {
    let out = sixaxis(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

fn fails_with(args: &[&str], code: i32, needles: &[&str]) {
    let out = sixaxis(args);
    assert_eq!(out.status.code(), Some(code), "{args:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "stderr {err:?} should name {n:?}");
    }
}

const BETA0: &str = "57.9948,-10.1070,-132.9377,53.0502,90.0002,32.0054";

#[test]
fn fk_of_beta0() {
    let v = ok_json(&["fk", "--joints-deg", BETA0]);
    let p: Vec<f64> = serde_json::from_value(v["position_mm"].clone()).unwrap();
    assert!(
        (p[0]).abs() < 0.1 && (p[1] + 200.0).abs() < 0.1 && (p[2] - 400.0).abs() < 0.1,
        "{p:?}"
    );
    let r: Vec<Vec<f64>> = serde_json::from_value(v["rotation"].clone()).unwrap();
    for (i, row) in r.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            assert!((x - if i == j { 1.0 } else { 0.0 }).abs() < 1e-4);
        }
    }
    let pts: Vec<[f64; 3]> = serde_json::from_value(v["points_mm"].clone()).unwrap();
    assert_eq!(pts.len(), 8);
    assert_eq!(pts[0], [0.0, 0.0, 0.0]);
    assert_eq!(pts[7], [p[0], p[1], p[2]]);
}

#[test]
fn lists_may_start_with_a_minus_sign() {
    let a = ok_json(&["fk", "--joints-deg", "-10,20,-30,40,-50,60"]);
    let b = ok_json(&["fk", "--joints-deg=-10,20,-30,40,-50,60"]);
    assert_eq!(a, b);
    let ik = ok_json(&["ik", "--position-mm", "0,-200,400", "--rpy-deg=0,0,0"]);
    let sols: Vec<[f64; 6]> = serde_json::from_value(ik["solutions_rad"].clone()).unwrap();
    assert!(!sols.is_empty() && sols.len() <= 8);
    let beta0: Vec<f64> = BETA0
        .split(',')
        .map(|x| x.parse::<f64>().unwrap().to_radians())
        .collect();
    assert!(
        sols.iter()
            .any(|q| q.iter().zip(&beta0).all(|(a, b)| (a - b).abs() < 1e-3)),
        "beta_0 is among the IK solutions of its own pose"
    );
}

#[test]
fn bad_arguments_name_the_flag() {
    fails_with(
        &["fk", "--joints-deg", "1,2,3"],
        2,
        &["--joints-deg", "expected 6"],
    );
    fails_with(
        &["ik", "--position-mm", "0,x,400"],
        2,
        &["--position-mm", "`x`"],
    );
    fails_with(
        &["train", "--scenario", "nowhere"],
        2,
        &["nowhere", "paper_simple"],
    );
    // Named as in Python (`episodes`): the CLI and the bindings share the core's request.
    fails_with(
        &["train", "--episodes", "0"],
        2,
        &["`episodes` = 0", "1..=4294967295"],
    );
}

#[test]
fn validate_reports_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.json");
    let mut s: Value = ok_json(&["validate", "paper_simple"]);
    s["start"] = serde_json::json!([0, 1, 0]);
    std::fs::write(&f, s.to_string()).unwrap();
    fails_with(
        &["validate", f.to_str().unwrap()],
        2,
        &["`start`", "[0, 1, 0]", "obstacle"],
    );
    std::fs::write(&f, "{ not json").unwrap();
    fails_with(
        &["validate", f.to_str().unwrap()],
        2,
        &["could not be parsed"],
    );
}

#[test]
fn train_json_and_atomic_out() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run.json");
    let q = dir.path().join("q.bin");
    let o = sixaxis(&[
        "train",
        "--scenario",
        "paper_simple",
        "--seed",
        "1",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--q-out",
        q.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stdout.is_empty(), "with --out nothing goes to stdout");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["reached"], true);
    assert_eq!(v["path_length"], v["shortest_path_length"]);
    assert_eq!(v["steps_per_episode"].as_array().unwrap().len(), 10000);
    assert!(v["converged_episode"].as_u64().is_some());
    let by_length = v["length_converged_episode"].as_u64().unwrap();
    assert!(by_length <= v["converged_episode"].as_u64().unwrap());
    assert!(v["wall_time_s"].as_f64().unwrap() > 0.0);
    // Only the two result files are left in the directory: no temporary files.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    // Same seed, same run (wall time aside).
    let again = ok_json(&["train", "--scenario", "paper_simple", "--seed", "1", "-q"]);
    for k in [
        "path",
        "steps_per_episode",
        "converged_episode",
        "total_steps",
    ] {
        assert_eq!(v[k], again[k], "{k}");
    }
    // Resume from the saved table.
    let resumed = ok_json(&[
        "train",
        "--scenario",
        "paper_simple",
        "--episodes",
        "10",
        "-q",
        "--no-curve",
        "--q-in",
        q.to_str().unwrap(),
    ]);
    assert_eq!(resumed["reached"], true);
    // A table saved for one scenario does not load for another.
    fails_with(
        &[
            "train",
            "--scenario",
            "replan_clutter",
            "-q",
            "--q-in",
            q.to_str().unwrap(),
        ],
        2,
        &["Q-table does not match"],
    );
    // An --out into a missing directory fails cleanly and writes nothing.
    let missing = dir.path().join("no/such/dir/run.json");
    fails_with(
        &[
            "train",
            "--episodes",
            "5",
            "-q",
            "--out",
            missing.to_str().unwrap(),
        ],
        2,
        &["run.json"],
    );
}

#[test]
fn plan_json_contract() {
    let v = ok_json(&["plan", "--scenario", "paper_simple", "--seed", "0", "-q"]);
    for key in [
        "success",
        "cell_mm",
        "arm_safe_distance",
        "interpolation_steps",
        "obstacles",
        "obstacle_boxes_mm",
        "path",
        "poses_rad",
        "replans",
        "added_obstacles",
        "failure",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["success"], true);
    assert_eq!(v["cell_mm"], 100.0);
    assert_eq!(v["interpolation_steps"], 50);
    assert_eq!(v["arm_safe_distance"], 0.76);
    assert_eq!(v["failure"], Value::Null);
    assert_eq!(v["obstacles"].as_array().unwrap().len(), 19);
    assert_eq!(
        v["obstacle_boxes_mm"],
        serde_json::json!([]),
        "a world of cells only"
    );
    assert_eq!(
        v["poses_rad"].as_array().unwrap().len(),
        v["path"].as_array().unwrap().len()
    );
    assert_eq!(v["poses_rad"][0].as_array().unwrap().len(), 6);

    let r = ok_json(&["plan", "--scenario", "replan_clutter", "--seed", "0", "-q"]);
    assert!(r["replans"].as_u64().unwrap() >= 1);
    assert_eq!(
        r["obstacles"].as_array().unwrap().len(),
        21,
        "the scenario's own, before any were added"
    );

    // A failed plan still prints its JSON, names the points on stderr, exits 1.
    let out = sixaxis(&[
        "plan",
        "--scenario",
        "replan_clutter",
        "--max-replans",
        "0",
        "-q",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["success"], false);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("re-plan cap (0) reached") && err.contains("could not be reached"),
        "{err}"
    );
}

#[test]
fn generate_writes_a_loadable_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("gen.json");
    let o = sixaxis(&["generate", "--seed", "3", "--out", f.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let from_file = ok_json(&["validate", f.to_str().unwrap()]);
    let by_name = ok_json(&["validate", "generated:3"]);
    assert_eq!(from_file, by_name);
    let reach = ok_json(&["reach", "--scenario", "paper_simple"]);
    assert_eq!(reach["free_cells"], 485);
    assert!((reach["target_best_clearance_cells"].as_f64().unwrap() - 0.75f64.sqrt()).abs() < 1e-9);
}

#[test]
fn reproduce_expands_generated_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let report = dir.path().join("REPORT.md");
    let v = ok_json(&[
        "reproduce",
        "--scenarios",
        "generated:0..1",
        "--seeds",
        "1",
        "--episodes",
        "30",
        "--no-figures",
        "-q",
        "--out-dir",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    let names: Vec<&str> = v["summary"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["scenario"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["generated:0", "generated:1"]);
    let full: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("reproduction.json")).unwrap())
            .unwrap();
    let assisted = &full["scenarios"][0]["assisted"];
    assert!(assisted["runs"][0]
        .get("length_converged_episode")
        .is_some());
    assert!(assisted.get("length_converged_episode_mean").is_some());
    fails_with(
        &["reproduce", "--scenarios", "generated:3..1", "--seeds", "1"],
        2,
        &["generated:3..1", "A <= B"],
    );
}
