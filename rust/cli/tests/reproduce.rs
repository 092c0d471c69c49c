//! `sixaxis reproduce` as a user runs it: the statistics of `reproduction.json` follow from
//! its runs, the report shows them, and `--episodes` is checked by the core's request layer
//! (the same error as `sixaxis train --episodes`).

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

fn sixaxis(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sixaxis"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// `reproduce` into `dir` (no figures, quiet); the JSON file and the report.
fn reproduce(dir: &Path, extra: &[&str]) -> (Value, String) {
    let out = dir.join("out");
    let report = dir.join("REPORT.md");
    let mut args = vec![
        "reproduce",
        "--no-figures",
        "-q",
        "--out-dir",
        out.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = sixaxis(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = std::fs::read_to_string(out.join("reproduction.json")).unwrap();
    (
        serde_json::from_str(&json).unwrap(),
        std::fs::read_to_string(report).unwrap(),
    )
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is a number"))
}

#[test]
fn statistics_follow_from_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let (v, report) = reproduce(
        dir.path(),
        &[
            "--scenarios",
            "paper_simple",
            "--seeds",
            "3",
            "--episodes",
            "300",
        ],
    );
    assert_eq!(v["episodes"], 300);
    let s = &v["scenarios"][0];
    for key in ["assisted", "unassisted"] {
        let c = &s[key];
        let runs = c["runs"].as_array().unwrap();
        assert_eq!(runs.len(), 3);
        let seeds: Vec<u64> = runs.iter().map(|r| r["seed"].as_u64().unwrap()).collect();
        assert_eq!(seeds, [0, 1, 2]);
        // Only seed 0 keeps its path and curve; no run its per-episode success.
        assert!(runs[0].get("path").is_some() && runs[0].get("steps_per_episode").is_some());
        assert!(runs[1..]
            .iter()
            .all(|r| r.get("path").is_none() && r.get("steps_per_episode").is_none()));
        assert!(runs.iter().all(|r| r.get("reached_per_episode").is_none()));
        let times: Vec<f64> = runs.iter().map(|r| f(&r["wall_time_s"])).collect();
        let m = times.iter().sum::<f64>() / 3.0;
        assert!((f(&c["wall_time_s_mean"]) - m).abs() <= 1e-12 * m.max(1.0));
        let var = times.iter().map(|t| (t - m).powi(2)).sum::<f64>() / 2.0;
        assert!((f(&c["wall_time_s_std"]) - var.sqrt()).abs() <= 1e-12);
        let steps: Vec<f64> = runs.iter().map(|r| f(&r["total_steps"])).collect();
        let steps_mean = steps.iter().sum::<f64>() / 3.0;
        assert_eq!(f(&c["total_steps_mean"]), steps_mean);
        // Every run has 300 episodes, so the mean curve sums to the mean of the totals.
        let curve = c["mean_steps_per_episode"].as_array().unwrap();
        assert_eq!(curve.len(), 300);
        let curve_sum: f64 = curve.iter().map(f).sum();
        assert!(
            (curve_sum - steps_mean).abs() < 1e-6,
            "{curve_sum} vs {steps_mean}"
        );
        let reached = runs.iter().filter(|r| r["reached"] == true).count();
        assert_eq!(c["reached"], reached);
        // The report's table of learned paths shows the count.
        let cond = if key == "assisted" {
            "with assistance"
        } else {
            "without"
        };
        let row = format!("| paper_simple | 9 | {cond} | {reached}/3 |");
        assert!(report.contains(&row), "{row} in\n{report}");
    }
    // One plan per seed, each with the three modes; only seed 0 has the full result.
    let plans = s["plans"].as_array().unwrap();
    assert_eq!(plans.len(), 3);
    for (seed, p) in plans.iter().enumerate() {
        assert_eq!(p["seed"], seed);
        for m in ["paper", "backtracking", "fixed_nd"] {
            assert_eq!(p["modes"][m]["seed"], seed, "{m}");
        }
        assert_eq!(p.get("result").is_some(), seed == 0);
        assert_eq!(p.get("arm_points_mm").is_some(), seed == 0);
    }
    assert_eq!(s["default_mode"], "paper");
    assert!(report.contains("| paper_simple | paper | backtracking | "));
}

#[test]
fn episodes_go_through_the_request_layer() {
    let dir = tempfile::tempdir().unwrap();
    for bad in ["0", "-3", "lots"] {
        let o = sixaxis(&[
            "reproduce",
            "--seeds",
            "1",
            "--episodes",
            bad,
            "--no-figures",
            "-q",
            "--out-dir",
            dir.path().to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "--episodes {bad}");
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        let train = sixaxis(&["train", "--episodes", bad, "-q"]);
        assert_eq!(train.status.code(), Some(2));
        assert_eq!(
            err,
            String::from_utf8_lossy(&train.stderr),
            "--episodes {bad}"
        );
        assert!(err.contains(&format!("`episodes` = {bad}")), "{err}");
        assert!(!dir.path().join("reproduction.json").exists());
    }
    // `auto`, as for `sixaxis train`: the runs stop when the greedy path settles.
    let (v, report) = reproduce(
        dir.path(),
        &[
            "--scenarios",
            "paper_simple",
            "--seeds",
            "1",
            "--episodes",
            "auto",
        ],
    );
    assert_eq!(v["episodes"], "auto");
    let run = &v["scenarios"][0]["assisted"]["runs"][0];
    assert_eq!(run["episodes_auto"], true);
    assert!(run["episodes_run"].as_u64().unwrap() < 1_000_000);
    assert!(report.contains("1 seeds (0..0) per condition, auto episodes per run"));
}
