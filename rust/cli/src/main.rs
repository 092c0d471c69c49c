//! The `sixaxis` command: kinematics, scenario validation, training, planning and the
//! paper's experiments, with JSON on stdout or to `--out FILE` (written atomically).
//!
//! Errors go to stderr with exit code 2 (bad input) or 1 (a run that failed), never a
//! panic backtrace. Ctrl-C exits with 130 at once, never inside an output write
//! (`interrupt`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use serde_json::{json, Value};
use sixaxis_core::kinematics::{rotation_from_rpy_deg, Arm};
use sixaxis_core::{Error, Scenario, TerminalPose};

mod flags;
mod interrupt;
mod learn;
mod list;
mod progress;
mod reproduce;
mod serve;

/// Six-axis arm path planning with Q-learning and whole-arm obstacle avoidance.
#[derive(Parser, Debug)]
#[command(name = "sixaxis", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Where a command's JSON goes.
#[derive(Args, Debug, Clone)]
struct OutArgs {
    /// Write the JSON to this file (atomically) instead of stdout.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Forward kinematics of the paper's arm.
    ///
    /// Example: sixaxis fk --joints-deg 57.9948,-10.1070,-132.9377,53.0502,90.0002,32.0054
    Fk {
        /// Six joint angles, degrees, comma-separated (may start with a minus sign).
        #[arg(long, value_name = "A,B,C,D,E,F", allow_hyphen_values = true)]
        joints_deg: String,
        /// Use the arm of this scenario (name or file) instead of the paper's.
        #[arg(long, value_name = "NAME_OR_FILE")]
        scenario: Option<String>,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Inverse kinematics: every closed-form solution (up to 8) for a terminal pose.
    ///
    /// Example: sixaxis ik --position-mm 0,-200,400 --rpy-deg 0,0,0
    Ik {
        /// Terminal position x,y,z in mm.
        #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
        position_mm: String,
        /// Terminal orientation rt_x,rt_y,rt_z in degrees, R = Rz(rt_z) Ry(rt_y) Rx(rt_x).
        #[arg(
            long,
            value_name = "RX,RY,RZ",
            allow_hyphen_values = true,
            default_value = "0,0,0"
        )]
        rpy_deg: String,
        /// Use the arm of this scenario (name or file) instead of the paper's.
        #[arg(long, value_name = "NAME_OR_FILE")]
        scenario: Option<String>,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Check a scenario file (or built-in name) and print it back with every default filled in.
    ///
    /// Example: sixaxis validate envs/paper_simple.json
    Validate {
        /// Scenario file or built-in name (paper_simple, paper_complex, replan_clutter).
        scenario: String,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Learn a terminal path with tabular Q-learning (eqs. 5-10).
    ///
    /// Example: sixaxis train --scenario paper_simple --seed 0 --no-assist --out run.json
    Train {
        #[command(flatten)]
        args: learn::TrainArgs,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Learn a path, plan the arm's poses, re-plan around unreachable points (Algorithm 2).
    ///
    /// Exit code 1 (and the JSON with "success": false and a "failure" reason) when no plan is found.
    ///
    /// Example: sixaxis plan --scenario paper_complex --seed 0 --out plan.json
    Plan {
        #[command(flatten)]
        args: learn::PlanArgs,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Which free cells a clear arm pose reaches, and the best clearance at the target.
    ///
    /// Example: sixaxis reach --scenario paper_complex
    Reach {
        /// Scenario file or built-in name.
        #[arg(long, value_name = "NAME_OR_FILE", default_value = "paper_simple")]
        scenario: String,
        #[command(flatten)]
        out: OutArgs,
    },
    /// A random cluttered scenario (start and target connected and reachable by the arm).
    ///
    /// Example: sixaxis generate --seed 3 --density 0.1 --out envs/mine.json
    Generate {
        /// Seed; `generated:SEED` names the same scenario at the default density and bounds.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[command(flatten)]
        options: flags::GeneratorFlags,
        #[command(flatten)]
        out: OutArgs,
    },
    /// The same physical world at another cell size (prints the new scenario's JSON)
    ///
    /// Obstacle boxes and safe distances are kept in mm, start and target at the same points
    /// (an error if they are not cell centres of the new grid).
    ///
    /// Example: sixaxis regrid --scenario paper_simple --cell-mm 50 --out simple_50mm.json
    Regrid {
        /// Scenario file or built-in name.
        #[arg(long, value_name = "NAME_OR_FILE")]
        scenario: String,
        /// Edge of a cell of the new grid, mm.
        #[arg(long, value_name = "MM")]
        cell_mm: f64,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Export a scenario: the arm as URDF, or the arm and its obstacles as a MuJoCo MJCF scene.
    ///
    /// The XML goes to stdout or to --out FILE (written atomically). Lengths in metres.
    ///
    /// Example: sixaxis export --format mjcf --scenario paper_simple --out paper_simple.xml
    Export {
        /// urdf (the arm) or mjcf (the arm, obstacles, target and start).
        #[arg(long, value_name = "urdf|mjcf")]
        format: String,
        /// Scenario file or built-in name.
        #[arg(long, value_name = "NAME_OR_FILE", default_value = "paper_simple")]
        scenario: String,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Run the paper's experiments: JSON, figures and docs/REPRODUCTION.md.
    ///
    /// Example: sixaxis reproduce --seeds 10 --out-dir results/reproduce
    Reproduce {
        #[command(flatten)]
        args: reproduce::ReproduceArgs,
        #[command(flatten)]
        out: OutArgs,
    },
    /// Serve the env over dm_env_rpc v1 (gRPC): worlds of the Gymnasium env for clients in
    /// other processes, machines or languages (docs/SERVER.md).
    ///
    /// Prints {"address": ..., "port": ...} on stdout once it listens; SIGTERM drains it.
    ///
    /// Example: sixaxis serve --address 127.0.0.1:50051
    Serve {
        #[command(flatten)]
        args: serve::ServeArgs,
    },
}

/// A failure that ends the command: bad input (exit 2) or a run that did not succeed (exit 1).
enum Failure {
    Input(Error),
    Run(String),
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure::Input(e)
    }
}

fn arm_of(scenario: &Option<String>) -> Result<Arm, Failure> {
    Ok(match scenario {
        Some(s) => Scenario::load(s)?.arm(),
        None => Arm::paper(),
    })
}

fn emit(value: &Value, out: &OutArgs) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(value).expect("JSON values always serialise") + "\n";
    emit_text(&text, out)
}

fn emit_text(text: &str, out: &OutArgs) -> Result<(), Failure> {
    interrupt::writing(|| match &out.out {
        Some(path) => sixaxis_core::io::write_atomic(path, text.as_bytes()),
        None => {
            print!("{text}");
            Ok(())
        }
    })?;
    Ok(())
}

fn mat_rows(m: &nalgebra::Matrix3<f64>) -> Value {
    json!((0..3)
        .map(|r| (0..3).map(|c| m[(r, c)]).collect::<Vec<_>>())
        .collect::<Vec<_>>())
}

/// `sixaxis reach`: arm reachability of every free cell.
fn reach(name: &str) -> Result<Value, Failure> {
    let s = Scenario::load(name)?;
    let planner = sixaxis_core::PosePlanner::from_scenario(&s);
    let world = sixaxis_core::GridWorld::new(&s)?;
    let mut no_ik = Vec::new();
    let mut unreachable = Vec::new();
    let mut free = 0usize;
    for state in 0..world.num_states() {
        if world.is_blocked(state) {
            continue;
        }
        free += 1;
        let c = world.cell_of(state);
        match planner.best_clearance_at(c) {
            None => no_ik.push(c),
            Some(_) if !planner.cell_reachable(c) => unreachable.push(c),
            Some(_) => {}
        }
    }
    let best = planner.best_clearance_at(s.target);
    Ok(json!({
        "scenario": s.name,
        "arm_safe_distance": s.arm_safe_distance,
        "free_cells": free,
        "no_ik_solution": no_ik,
        "no_clear_pose": unreachable,
        "target": s.target,
        "target_best_clearance_cells": best.map(|b| b.0),
        "target_best_pose_rad": best.map(|b| b.1),
        "target_best_rpy_deg": best.map(|b| b.2),
    }))
}

fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Fk {
            joints_deg,
            scenario,
            out,
        } => {
            let q = list::parse_fixed::<6>("--joints-deg", &joints_deg)?.map(f64::to_radians);
            let arm = arm_of(&scenario)?;
            let pose = arm.fk(&q);
            let pts = arm.points_mm(&q);
            emit(
                &json!({
                    "position_mm": [pose.position_mm.x, pose.position_mm.y, pose.position_mm.z],
                    "rotation": mat_rows(&pose.rotation),
                    "points_mm": pts.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
                }),
                &out,
            )
        }
        Command::Ik {
            position_mm,
            rpy_deg,
            scenario,
            out,
        } => {
            let p = list::parse_fixed::<3>("--position-mm", &position_mm)?;
            let rpy = list::parse_fixed::<3>("--rpy-deg", &rpy_deg)?;
            let arm = arm_of(&scenario)?;
            let target = TerminalPose {
                position_mm: nalgebra::Vector3::from(p),
                rotation: rotation_from_rpy_deg(rpy),
            };
            let sols = arm.ik(&target);
            emit(
                &json!({ "solutions_rad": sols.iter().map(|q| q.to_vec()).collect::<Vec<_>>() }),
                &out,
            )
        }
        Command::Validate { scenario, out } => {
            let s = Scenario::load(&scenario)?;
            emit(
                &serde_json::to_value(&s).expect("scenarios serialise"),
                &out,
            )
        }
        Command::Train { args, out } => emit(
            &serde_json::to_value(learn::run_train(&args)?).expect("a report serialises"),
            &out,
        ),
        Command::Plan { args, out } => {
            let r = learn::run_plan(&args)?;
            emit(
                &serde_json::to_value(&r).expect("plan results serialise"),
                &out,
            )?;
            match r.failure {
                Some(why) => Err(Failure::Run(why)),
                None => Ok(()),
            }
        }
        Command::Regrid {
            scenario,
            cell_mm,
            out,
        } => {
            let s = sixaxis_core::regrid::regrid(&Scenario::load(&scenario)?, cell_mm)?;
            emit_text(&(s.to_json() + "\n"), &out)
        }
        Command::Reproduce { args, out } => emit(
            &serde_json::to_value(reproduce::run(&args)?).expect("reproduce results serialise"),
            &out,
        ),
        Command::Reach { scenario, out } => emit(&reach(&scenario)?, &out),
        Command::Export {
            format,
            scenario,
            out,
        } => {
            let format: sixaxis_core::export::ExportFormat = format.parse()?;
            let s = Scenario::load(&scenario)?;
            emit_text(&sixaxis_core::export::export(&s, format), &out)
        }
        Command::Serve { args } => Ok(serve::run(&args)?),
        Command::Generate { seed, options, out } => {
            let opts =
                sixaxis_core::generator::GeneratorOptions::default().with(&options.options()?)?;
            let s = sixaxis_core::generator::generate(&opts, seed)?;
            emit(
                &serde_json::to_value(&s).expect("scenarios serialise"),
                &out,
            )
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // The server drains on SIGINT/SIGTERM itself (serve::run).
    if !matches!(cli.command, Command::Serve { .. }) {
        interrupt::install();
    }
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
        Err(Failure::Run(msg)) => {
            eprintln!("failed: {msg}");
            ExitCode::from(1)
        }
    }
}
