//! # sixaxis-core
//!
//! The pure-Rust core of SixAxisAvoid: a six-axis arm that learns to reach a target through
//! clutter, after *Path Planning with Autonomous Obstacle Avoidance Using Reinforcement
//! Learning for Six-axis Arms*. No Python here: the `sixaxis` binary and the
//! `sixaxis_avoid._core` extension are thin layers over this crate.
//!
//! Modules, in the order the method uses them:
//! - [`scenario`] — the world of one experiment, from JSON.
//! - [`grid`] — the terminal's grid world: actions, collisions, rewards (eqs. 5, 9, 10), BFS.
//! - [`qlearning`] — tabular Q-learning (eqs. 6-8), learned path, Q-table files.
//! - [`kinematics`] — D-H arm, forward kinematics, the arm's polyline, orientation grid.
//! - [`ik`] — closed-form inverse kinematics, every solution (up to 8).
//! - [`clearance`] — whole-arm clearance (eq. 11 and exact capsules), joint-space motion checks.
//! - [`planner`] — pose planning over a terminal path (Algorithm 1).
//! - [`replanning`] — the integrated loop with re-planning (Algorithm 2) over any
//!   [`PathLearner`] (tabular Q-learning by default, BFS, or your own).
//! - [`request`] — training and planning requests: the one place that checks the
//!   options of a run and fills their defaults (the CLI and the bindings map onto it).
//! - [`regrid`] — the same physical world at another cell size.
//! - [`generator`] — random cluttered scenarios for benchmarks.
//! - [`names`] — scenario names: files, built-ins, `generated:SEED`, `generated:A..B` lists.
//! - [`export`] — the arm as URDF, the arm and its world as a MuJoCo MJCF scene.
//! - [`mod@env`] — RL environment logic: episodes, observations, batched envs (for Python).
//! - [`joint_env`] — the joint-space environment: continuous actions checked by the exact
//!   capsule clearance.
//! - [`batch`] — N episodes stepped together (next-step autoreset, step cap): the one batch
//!   logic of both envs.
//! - [`error`] — the one error type; [`io`] — atomic file output; [`host`] — the
//!   machine description of reports.
//!
//! Layers, bottom up, without cycles: `scenario` (with `kinematics` and `ik` for its arm);
//! `grid`; `qlearning`; `clearance`; `planner`; `replanning`, `request`; `generator`;
//! `names`; `regrid` and `export` (each on `scenario` alone).
//!
//! Units: lengths in mm unless a name says cells; angles in radians unless a name says deg.
//!
//! ```
//! use sixaxis_core::{replanning::{plan, PlanOptions}, Scenario};
//! let s = Scenario::load("paper_simple").unwrap();
//! let result = plan(&s, &PlanOptions::from_scenario(&s), None, None).unwrap();
//! assert!(result.success, "{:?}", result.failure);
//! assert_eq!(result.poses_rad.len(), result.path.len());
//! ```

#![warn(missing_docs)]

pub mod batch;
pub mod clearance;
pub mod env;
pub mod error;
pub mod export;
pub mod generator;
pub mod grid;
pub mod host;
pub mod ik;
pub mod io;
pub mod joint_env;
pub mod kinematics;
pub mod names;
pub mod options;
pub mod planner;
pub mod qlearning;
pub mod regrid;
pub mod replanning;
pub mod request;
pub mod scenario;
pub mod tables;

pub use clearance::Clearance;
pub use error::{Error, Result};
pub use grid::{Assist, GridWorld, Transition};
pub use ik::{check_closed_form_family, IkSolutions};
pub use kinematics::{Arm, Joints, TerminalPose};
pub use planner::{PosePlan, PosePlanner, PosePoint};
pub use qlearning::{greedy_path, train, Learning, QTable, TrainReport, TrainResult};
pub use replanning::{
    plan, BfsLearner, LearnedPath, PathLearner, PlanOptions, PlanResult, QLearner,
};
pub use scenario::{Cell, Scenario};
