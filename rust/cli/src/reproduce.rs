//! `sixaxis reproduce`: the paper's experiments (simple and complex obstacles, with and
//! without assisted learning, over several seeds) plus our own re-plan scenario.
//!
//! Writes `reproduction.json` into `--out-dir`, draws the figures with
//! `scripts/reproduce_figures.py` (matplotlib) and writes the report `docs/REPRODUCTION.md`.
//! Runs are sequential so that wall times are not disturbed by each other.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use clap::Args;
use serde_json::{json, Value};
use sixaxis_core::grid::{Assist, GridWorld};
use sixaxis_core::qlearning::{train, TrainOptions};
use sixaxis_core::replanning::{plan, PlanOptions, PlanResult};
use sixaxis_core::{Error, Scenario};

use crate::progress;
use crate::Failure;

/// Flags of `sixaxis reproduce`.
#[derive(Args, Debug, Clone)]
pub struct ReproduceArgs {
    /// Scenarios to run (built-in names or files), comma-separated.
    #[arg(long, default_value = "paper_simple,paper_complex,replan_clutter")]
    pub scenarios: String,
    /// Seeds 0..N per experiment.
    #[arg(long, default_value_t = 10)]
    pub seeds: u64,
    /// Learning episodes per run (default: each scenario's, the paper's 10000).
    #[arg(long)]
    pub episodes: Option<u32>,
    /// Where the JSON and the figures go.
    #[arg(long, default_value = "results/reproduce")]
    pub out_dir: PathBuf,
    /// Where the report goes.
    #[arg(long, default_value = "docs/REPRODUCTION.md")]
    pub report: PathBuf,
    /// The figure script (Python with matplotlib).
    #[arg(long, default_value = "scripts/reproduce_figures.py")]
    pub figures_script: PathBuf,
    /// Python interpreter for the figure script.
    #[arg(long, default_value = "python3")]
    pub python: String,
    /// Skip the figures (JSON and report only).
    #[arg(long)]
    pub no_figures: bool,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
}

/// The paper's learning times, seconds: (scenario, without assistance, with assistance).
const PAPER_TIMES_S: [(&str, f64, f64); 2] = [
    ("paper_simple", 2151.219, 1268.14),
    ("paper_complex", 1661.722, 725.996),
];

fn mean(xs: &[f64]) -> f64 {
    if xs.is_empty() {
        f64::NAN
    } else {
        xs.iter().sum::<f64>() / xs.len() as f64
    }
}

fn std_dev(xs: &[f64]) -> f64 {
    if xs.len() < 2 {
        return 0.0;
    }
    let m = mean(xs);
    (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!(
        "{cpu}, {cores} cores, {} {}",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// One learning condition over all seeds.
fn learn_condition(
    s: &Scenario,
    world: &GridWorld,
    assist: Assist,
    a: &ReproduceArgs,
    pb: &indicatif::ProgressBar,
) -> Result<Value, Failure> {
    let mut runs = Vec::new();
    let mut curve_sum: Vec<f64> = Vec::new();
    for seed in 0..a.seeds {
        let mut opts = TrainOptions::from_scenario(s);
        opts.seed = seed;
        opts.assist = assist;
        if let Some(n) = a.episodes {
            opts.episodes = n;
        }
        let r = train(world, &opts, None, None)?;
        if curve_sum.is_empty() {
            curve_sum = vec![0.0; r.steps_per_episode.len()];
        }
        for (acc, &n) in curve_sum.iter_mut().zip(&r.steps_per_episode) {
            *acc += n as f64;
        }
        let mut v = crate::learn::train_json(s, world, &opts, &r, seed == 0);
        if seed != 0 {
            v.as_object_mut().expect("an object").remove("path");
        }
        runs.push(v);
        pb.inc(1);
    }
    let n = a.seeds.max(1) as f64;
    let times: Vec<f64> = runs
        .iter()
        .map(|r| r["wall_time_s"].as_f64().unwrap_or(f64::NAN))
        .collect();
    let steps: Vec<f64> = runs
        .iter()
        .map(|r| r["total_steps"].as_f64().unwrap_or(f64::NAN))
        .collect();
    let reached = runs.iter().filter(|r| r["reached"] == json!(true)).count();
    let lengths: Vec<f64> = runs
        .iter()
        .filter_map(|r| r["path_length"].as_f64())
        .collect();
    let conv: Vec<f64> = runs
        .iter()
        .filter_map(|r| r["converged_episode"].as_f64())
        .collect();
    Ok(json!({
        "assist": assist,
        "runs": runs,
        "reached": reached,
        "wall_time_s_mean": mean(&times),
        "wall_time_s_std": std_dev(&times),
        "total_steps_mean": mean(&steps),
        "path_length_mean": mean(&lengths),
        "converged_episode_mean": mean(&conv),
        "mean_steps_per_episode": curve_sum.iter().map(|x| x / n).collect::<Vec<_>>(),
    }))
}

fn plan_json(s: &Scenario, r: &PlanResult, detailed: bool) -> Value {
    let mut v = json!({
        "seed": r.seed,
        "success": r.success,
        "replans": r.replans,
        "added_obstacles": r.added_obstacles,
        "failure": r.failure,
        "path_length": if r.path.is_empty() { Value::Null } else { json!(r.path.len() - 1) },
        "wall_time_s": r.wall_time_s,
    });
    if detailed {
        let arm = s.arm();
        let points: Vec<Vec<[f64; 3]>> = r
            .poses_rad
            .iter()
            .map(|q| arm.points_mm(q).iter().map(|p| [p.x, p.y, p.z]).collect())
            .collect();
        v["result"] = serde_json::to_value(r).expect("plan results serialise");
        v["arm_points_mm"] = json!(points);
    }
    v
}

/// `sixaxis reproduce`.
pub fn run(a: &ReproduceArgs) -> Result<Value, Failure> {
    if a.seeds == 0 {
        return Err(Error::argument("--seeds", 0, "must be > 0").into());
    }
    let names: Vec<&str> = a
        .scenarios
        .split(',')
        .map(str::trim)
        .filter(|n| !n.is_empty())
        .collect();
    let scenarios = names
        .iter()
        .map(|n| Scenario::load(n))
        .collect::<Result<Vec<_>, _>>()?;
    let total = scenarios.len() as u64 * a.seeds * 3;
    let pb = progress::bar(total, "reproducing", a.quiet);
    let mut out = Vec::new();
    for s in &scenarios {
        pb.set_message(s.name.clone());
        let world = GridWorld::new(s)?;
        let assisted = learn_condition(s, &world, Assist::on(), a, &pb)?;
        let unassisted = learn_condition(s, &world, Assist::off(), a, &pb)?;
        let mut plans = Vec::new();
        for seed in 0..a.seeds {
            let mut opts = PlanOptions::from_scenario(s);
            opts.train.seed = seed;
            opts.train.assist = Assist::on();
            if let Some(n) = a.episodes {
                opts.train.episodes = n;
            }
            let r = plan(s, &opts, None)?;
            let mut entry = plan_json(s, &r, seed == 0);
            // The paper's Algorithm 1 as written: the greedy pass, no backtracking.
            let mut greedy_scenario = s.clone();
            greedy_scenario.planning.backtrack_budget = 0;
            let g = plan(&greedy_scenario, &opts, None)?;
            entry["greedy"] = plan_json(s, &g, false);
            plans.push(entry);
            pb.inc(1);
        }
        out.push(json!({
            "name": s.name,
            "notes": s.notes,
            "bounds": s.bounds,
            "start": s.start,
            "target": s.target,
            "obstacles": s.obstacles,
            "terminal_safe_distance": s.terminal_safe_distance,
            "arm_safe_distance": s.arm_safe_distance,
            "shortest_path": world.shortest_path(),
            "shortest_path_length": world.shortest_path().map(|p| p.len() - 1),
            "assisted": assisted,
            "unassisted": unassisted,
            "plans": plans,
        }));
    }
    pb.finish_and_clear();
    let result = json!({
        "machine": machine(),
        "seeds": a.seeds,
        "episodes": a.episodes,
        "build": if cfg!(debug_assertions) { "debug" } else { "release" },
        "scenarios": out,
    });
    std::fs::create_dir_all(&a.out_dir).map_err(|e| Error::io(&a.out_dir, e))?;
    let json_path = a.out_dir.join("reproduction.json");
    let text = serde_json::to_string(&result).expect("JSON values serialise");
    crate::interrupt::writing(|| sixaxis_core::io::write_atomic(&json_path, text.as_bytes()))?;
    let figures = if a.no_figures {
        None
    } else {
        Some(draw_figures(a, &json_path)?)
    };
    let report = report(&result, figures.as_deref(), &json_path, a);
    if let Some(dir) = a.report.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
    }
    crate::interrupt::writing(|| sixaxis_core::io::write_atomic(&a.report, report.as_bytes()))?;
    Ok(json!({
        "results": json_path,
        "report": a.report,
        "figures": figures,
        "summary": summary(&result),
    }))
}

fn draw_figures(a: &ReproduceArgs, json_path: &Path) -> Result<PathBuf, Failure> {
    let status = Command::new(&a.python)
        .arg(&a.figures_script)
        .arg("--results")
        .arg(json_path)
        .arg("--out-dir")
        .arg(&a.out_dir)
        .status()
        .map_err(|e| {
            Failure::Run(format!(
                "could not start `{} {}`: {e} (use --no-figures to skip the figures)",
                a.python,
                a.figures_script.display()
            ))
        })?;
    if !status.success() {
        return Err(Failure::Run(format!(
            "the figure script `{}` failed ({status}); the JSON is in {}",
            a.figures_script.display(),
            json_path.display()
        )));
    }
    Ok(a.out_dir.clone())
}

fn summary(result: &Value) -> Value {
    let rows: Vec<Value> = result["scenarios"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|s| {
            let with = s["assisted"]["wall_time_s_mean"]
                .as_f64()
                .unwrap_or(f64::NAN);
            let without = s["unassisted"]["wall_time_s_mean"]
                .as_f64()
                .unwrap_or(f64::NAN);
            let plans = s["plans"].as_array().cloned().unwrap_or_default();
            json!({
                "scenario": s["name"],
                "learning_time_s_assisted": with,
                "learning_time_s_unassisted": without,
                "ratio_unassisted_over_assisted": without / with,
                "plans_succeeded": plans.iter().filter(|p| p["success"] == json!(true)).count(),
                "plans": plans.len(),
                "replans_seed0": plans.first().map(|p| p["replans"].clone()),
            })
        })
        .collect();
    json!(rows)
}

fn fmt_opt(v: &Value, digits: usize) -> String {
    match v.as_f64() {
        Some(x) if x.is_finite() => format!("{x:.digits$}"),
        _ => "—".into(),
    }
}

fn report(result: &Value, figures: Option<&Path>, json_path: &Path, a: &ReproduceArgs) -> String {
    let mut r = String::new();
    let seeds = result["seeds"].as_u64().unwrap_or(0);
    let _ = writeln!(r, "# Reproduction of the paper's experiments\n");
    let _ = writeln!(
        r,
        "Generated by `sixaxis reproduce` ({} build) on {}; {} seeds (0..{}) per condition, {} episodes per run. Raw data: `{}`.\n",
        result["build"].as_str().unwrap_or("?"),
        result["machine"].as_str().unwrap_or("?"),
        seeds,
        seeds.saturating_sub(1),
        a.episodes.map_or("the scenario's".to_string(), |n| n.to_string()),
        json_path.display()
    );
    let _ = writeln!(r, "## Learning time with and without assisted learning\n");
    let _ = writeln!(r, "The paper reports one run per condition in seconds (its own implementation and machine); ours is the mean ± standard deviation over seeds, in milliseconds, of the native Rust learner on one core. Absolute times are not comparable; the ratios are the figures to compare. Wall times of a few milliseconds move with the machine's load; the environment-step ratio does not, and is the machine-independent measure of the speed-up.\n");
    let _ = writeln!(r, "| scenario | paper: without (s) | paper: with (s) | paper ratio | ours: without (ms) | ours: with (ms) | our time ratio | env steps without | env steps with | our step ratio |");
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|---|---|");
    for s in result["scenarios"].as_array().into_iter().flatten() {
        let name = s["name"].as_str().unwrap_or("?");
        let paper = PAPER_TIMES_S.iter().find(|(n, _, _)| *n == name);
        let (pw, pa, pr) = match paper {
            Some((_, w, wa)) => (
                format!("{w:.1}"),
                format!("{wa:.1}"),
                format!("{:.2}", w / wa),
            ),
            None => ("—".into(), "—".into(), "—".into()),
        };
        let ua = &s["unassisted"];
        let aa = &s["assisted"];
        let ratio = ua["wall_time_s_mean"].as_f64().unwrap_or(f64::NAN)
            / aa["wall_time_s_mean"].as_f64().unwrap_or(f64::NAN);
        let step_ratio = ua["total_steps_mean"].as_f64().unwrap_or(f64::NAN)
            / aa["total_steps_mean"].as_f64().unwrap_or(f64::NAN);
        let _ = writeln!(
            r,
            "| {name} | {pw} | {pa} | {pr} | {:.1} ± {:.1} | {:.1} ± {:.1} | {} | {} | {} | {} |",
            ua["wall_time_s_mean"].as_f64().unwrap_or(f64::NAN) * 1e3,
            ua["wall_time_s_std"].as_f64().unwrap_or(f64::NAN) * 1e3,
            aa["wall_time_s_mean"].as_f64().unwrap_or(f64::NAN) * 1e3,
            aa["wall_time_s_std"].as_f64().unwrap_or(f64::NAN) * 1e3,
            fmt_opt(&json!(ratio), 2),
            fmt_opt(&ua["total_steps_mean"], 0),
            fmt_opt(&aa["total_steps_mean"], 0),
            fmt_opt(&json!(step_ratio), 2),
        );
    }
    let _ = writeln!(r, "\n## Learned paths against the shortest path\n");
    let _ = writeln!(r, "The shortest terminal path is found by breadth-first search on the same grid (same collision rule). A learned path is the greedy rollout after training (eq. 8).\n");
    let _ = writeln!(r, "| scenario | shortest (steps) | condition | reached target | mean learned length | mean converged episode |");
    let _ = writeln!(r, "|---|---|---|---|---|---|");
    for s in result["scenarios"].as_array().into_iter().flatten() {
        for (cond, key) in [("with assistance", "assisted"), ("without", "unassisted")] {
            let c = &s[key];
            let _ = writeln!(
                r,
                "| {} | {} | {cond} | {}/{seeds} | {} | {} |",
                s["name"].as_str().unwrap_or("?"),
                fmt_opt(&s["shortest_path_length"], 0),
                c["reached"],
                fmt_opt(&c["path_length_mean"], 2),
                fmt_opt(&c["converged_episode_mean"], 0),
            );
        }
    }
    let _ = writeln!(
        r,
        "\n## Pose planning and re-planning (Algorithm 2, with assistance)\n"
    );
    let _ = writeln!(r, "The paper needed one re-plan in the complex case and none in the simple case. Our Algorithm 1 takes the first candidate pose whose motion is clear, as the paper's does, and backtracks to earlier points' next candidates only after a dead end (`planning.backtrack_budget`, 2000 motion checks by default). The last two columns run the paper's greedy pass alone (budget 0) on the same scenario and seed; ✗k marks a failed run after k re-plans.\n");
    let _ = writeln!(r, "| scenario | d_p (cells) | plans succeeded | re-plans per seed | points added (seed 0) | failure (seed 0) | greedy: succeeded | greedy: re-plans per seed |");
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|");
    for s in result["scenarios"].as_array().into_iter().flatten() {
        let plans = s["plans"].as_array().cloned().unwrap_or_default();
        let ok = plans.iter().filter(|p| p["success"] == json!(true)).count();
        let replans: Vec<String> = plans.iter().map(|p| p["replans"].to_string()).collect();
        let first = plans.first().cloned().unwrap_or(Value::Null);
        let greedy_ok = plans
            .iter()
            .filter(|p| p["greedy"]["success"] == json!(true))
            .count();
        let greedy_replans: Vec<String> = plans
            .iter()
            .map(|p| {
                let g = &p["greedy"];
                if g["success"] == json!(true) {
                    g["replans"].to_string()
                } else {
                    format!("✗{}", g["replans"])
                }
            })
            .collect();
        let _ = writeln!(
            r,
            "| {} | {} | {ok}/{} | {} | {} | {} | {greedy_ok}/{} | {} |",
            s["name"].as_str().unwrap_or("?"),
            s["arm_safe_distance"],
            plans.len(),
            replans.join(", "),
            first["added_obstacles"],
            first["failure"].as_str().unwrap_or("—"),
            plans.len(),
            greedy_replans.join(", "),
        );
    }
    if let Some(dir) = figures {
        let _ = writeln!(r, "\n## Figures\n");
        let _ = writeln!(r, "Drawn by `scripts/reproduce_figures.py` into `{}`; copies of the seed-0 figures are in `docs/figures/`.\n", dir.display());
        for s in result["scenarios"].as_array().into_iter().flatten() {
            let n = s["name"].as_str().unwrap_or("?");
            let _ = writeln!(r, "### {n}\n");
            let _ = writeln!(r, "![steps per episode](figures/{n}_steps.png)\n![terminal path](figures/{n}_path.png)\n![arm poses](figures/{n}_poses.png)\n");
        }
    }
    let _ = writeln!(r, "\n## Interpretations taken\n");
    let _ = writeln!(r, "See `docs/SCENARIOS.md` and `../shared/SPEC.md` section 2: modified D-H (Craig); 100 mm cells; d_s for the terminal during learning, d_p for the whole arm (eq. 11); obstacle (0,3,0) left out because it is the target; Table 3 shipped as printed (same obstacles as Table 1; with d_s 0.96 and 0.95 both block exactly the obstacle cells, so paper_simple and paper_complex are the same world for the learner and differ only in d_p for the arm); a collision leaves the terminal in place; epsilon falls linearly to 0 over M = 9900 episodes; episodes capped at `learning.max_steps_per_episode` steps; Algorithm 1 tries orientations by growing angle from the current one and IK solutions by joint distance, 50 interpolation steps; each re-plan learns from scratch.");
    r
}
