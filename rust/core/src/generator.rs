//! Random cluttered scenarios for benchmarking learners, deterministic per seed.
//!
//! Entry points:
//! - [`generate`] — one scenario from [`GeneratorOptions`] and a seed: unit-cube clutter at a
//!   given density inside given bounds, start and target connected (breadth-first search)
//!   and, by default, both reachable by a clear arm pose; beta_0 is the clearest pose at the
//!   start.
//! - [`benchmark_scenario`] — member `i` of the fixed benchmark set, also reachable as the
//!   scenario name `generated:i` ([`crate::scenario::Scenario::load`], in
//!   [`crate::names`], which also expands `generated:0..9` lists).
//!
//! ```
//! use sixaxis_core::generator::{generate, GeneratorOptions};
//! let s = generate(&GeneratorOptions::default(), 7).unwrap();
//! assert_eq!(s, generate(&GeneratorOptions::default(), 7).unwrap());
//! ```

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::grid::GridWorld;
use crate::options::{
    apply, check_all, Domain, FromOption, OptionInfo, OptionSpec, Options, ToOption,
};
use crate::planner::PosePlanner;
use crate::scenario::{Bounds, Cell, PoseSearchMode, Scenario};

/// Prefix of generated scenario names: `generated:SEED`.
pub const GENERATED_PREFIX: &str = "generated:";

/// How random scenarios are made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeneratorOptions {
    /// The grid, cells (inclusive box).
    pub bounds: Bounds,
    /// Fraction of the cells in bounds that become obstacles, in [0, 0.6].
    pub density: f64,
    /// Smallest straight-line distance between start and target, cells.
    pub min_start_target_distance: f64,
    /// Require a clear arm pose at the start and at the target.
    pub require_arm_reachable: bool,
    /// Attempts before giving up.
    pub max_attempts: u32,
    /// Every other field (rewards, learning, arm, safe distances, planning) comes from this
    /// scenario: a built-in name or a file ([`Scenario::open`]).
    pub template: String,
    /// Pose search of the generated scenarios: `Some((mode, n_d growth))` replaces the
    /// template's `planning.mode` and `planning.orientation_divisions_growth`; `None` keeps
    /// them. Default: backtracking with n_d fixed, which needed the fewest re-plans on the
    /// generated set (docs/SCENARIOS.md).
    pub pose_search: Option<(PoseSearchMode, u32)>,
}

impl Default for GeneratorOptions {
    fn default() -> Self {
        GeneratorOptions {
            bounds: Bounds {
                min: [-3, -3, -2],
                max: [3, 5, 5],
            },
            density: 0.08,
            min_start_target_distance: 4.0,
            require_arm_reachable: true,
            max_attempts: 200,
            template: "paper_simple".into(),
            pose_search: Some((PoseSearchMode::Backtracking, 1)),
        }
    }
}

/// The domain of `density`: a fraction of the cells, [0, 0.6].
const DENSITY: Domain = Domain::Float {
    min: 0.0,
    max: 0.6,
    open_min: false,
};
/// The domain of `min_start_target_distance`: at least one cell.
const MIN_DISTANCE: Domain = Domain::Float {
    min: 1.0,
    max: f64::INFINITY,
    open_min: false,
};

/// The options of [`generate`] a caller sets by key (the Python keywords of
/// `generate_scenario` and the flags of `sixaxis generate`), declared once; `bounds` (a
/// pair of cells, a Python keyword) and `pose_search` are set on [`GeneratorOptions`].
pub static GENERATOR_OPTIONS: [OptionSpec<GeneratorOptions>; 5] = [
    OptionSpec {
        info: OptionInfo {
            key: "density",
            field: "",
            domain: DENSITY,
            unit: "fraction of the cells",
            doc: "Fraction of the cells in bounds that become obstacles.",
        },
        get: |o| o.density.to_option(),
        set: |o, key, v| {
            o.density = f64::from_option(key, &DENSITY, v)?;
            Ok(())
        },
    },
    OptionSpec {
        info: OptionInfo {
            key: "min_start_target_distance",
            field: "",
            domain: MIN_DISTANCE,
            unit: "cells",
            doc: "Smallest straight-line distance between start and target.",
        },
        get: |o| o.min_start_target_distance.to_option(),
        set: |o, key, v| {
            o.min_start_target_distance = f64::from_option(key, &MIN_DISTANCE, v)?;
            Ok(())
        },
    },
    OptionSpec {
        info: OptionInfo {
            key: "require_arm_reachable",
            field: "",
            domain: Domain::Bool,
            unit: "",
            doc: "Require a clear arm pose at the start and at the target.",
        },
        get: |o| o.require_arm_reachable.to_option(),
        set: |o, key, v| {
            o.require_arm_reachable = bool::from_option(key, &Domain::Bool, v)?;
            Ok(())
        },
    },
    OptionSpec {
        info: OptionInfo {
            key: "max_attempts",
            field: "",
            domain: Domain::u32_from(1),
            unit: "draws",
            doc: "Draws of start, target and obstacles before giving up.",
        },
        get: |o| o.max_attempts.to_option(),
        set: |o, key, v| {
            o.max_attempts = u32::from_option(key, &Domain::u32_from(1), v)?;
            Ok(())
        },
    },
    OptionSpec {
        info: OptionInfo {
            key: "template",
            field: "",
            domain: Domain::Text,
            unit: "",
            doc: "The scenario (built-in name or file) every other field comes from: rewards, learning, arm, safe distances, planning.",
        },
        get: |o| o.template.to_option(),
        set: |o, key, v| {
            o.template = String::from_option(key, &Domain::Text, v)?;
            Ok(())
        },
    },
];

/// What each option of [`GENERATOR_OPTIONS`] is.
pub fn generator_options() -> Vec<OptionInfo> {
    GENERATOR_OPTIONS.iter().map(|s| s.info).collect()
}

impl GeneratorOptions {
    /// These options with `values` set by key (see [`GENERATOR_OPTIONS`]), each checked.
    pub fn with(mut self, values: &Options) -> Result<Self> {
        let table: Vec<&OptionSpec<GeneratorOptions>> = GENERATOR_OPTIONS.iter().collect();
        apply(&table, values, &mut self)?;
        Ok(self)
    }

    /// Check every keyed option against its domain; the error names the key.
    pub fn check(&self) -> Result<()> {
        check_all(&GENERATOR_OPTIONS, self, |i| i.key)
    }
}

/// Member `seed` of the fixed benchmark set (default options), named `generated:SEED`.
pub fn benchmark_scenario(seed: u64) -> Result<Scenario> {
    generate(&GeneratorOptions::default(), seed)
}

fn dist(a: Cell, b: Cell) -> f64 {
    let d: [f64; 3] = [0, 1, 2].map(|i| (a[i] - b[i]) as f64);
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
}

/// Generate one scenario. Deterministic: the same options and seed give the same scenario.
pub fn generate(opts: &GeneratorOptions, seed: u64) -> Result<Scenario> {
    opts.check()?;
    let template = Scenario::open(&opts.template)?;
    let b = opts.bounds;
    if (0..3).any(|i| b.min[i] > b.max[i]) {
        return Err(Error::argument(
            "bounds",
            format!("{:?}..{:?}", b.min, b.max),
            "empty box",
        ));
    }
    let mut cells: Vec<Cell> = Vec::with_capacity(b.volume());
    for x in b.min[0]..=b.max[0] {
        for y in b.min[1]..=b.max[1] {
            for z in b.min[2]..=b.max[2] {
                cells.push([x, y, z]);
            }
        }
    }
    if cells.len() < 2 {
        return Err(Error::argument(
            "bounds",
            cells.len(),
            "needs at least 2 cells",
        ));
    }
    let base: Cell = [0, 0, 0];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // One planner on the empty template world: reachability of a cell depends on obstacles,
    // so it is re-checked below on the generated world.
    for attempt in 0..opts.max_attempts {
        let n_obstacles = (opts.density * cells.len() as f64).round() as usize;
        let start = cells[rng.random_range(0..cells.len())];
        let target = cells[rng.random_range(0..cells.len())];
        if dist(start, target) < opts.min_start_target_distance || start == base || target == base {
            continue;
        }
        let mut pool: Vec<Cell> = cells
            .iter()
            .copied()
            .filter(|&c| c != start && c != target && c != base)
            .collect();
        pool.shuffle(&mut rng);
        pool.truncate(n_obstacles);
        pool.sort();
        let mut s = template.clone();
        if let Some((mode, growth)) = opts.pose_search {
            s.planning.mode = mode;
            s.planning.orientation_divisions_growth = growth;
        }
        s.name = format!("{GENERATED_PREFIX}{seed}");
        s.notes = format!(
            "Generated (seed {seed}, attempt {attempt}): density {}, bounds {:?}..{:?}, template {}; start and target connected (BFS){}; beta_0 is the clearest arm pose at the start.",
            opts.density,
            b.min,
            b.max,
            opts.template,
            if opts.require_arm_reachable { " and reachable by a clear arm pose" } else { "" }
        );
        s.bounds = b;
        s.start = start;
        s.target = target;
        s.obstacles = pool;
        // beta_0: the clearest pose at the start (also decides arm reachability of the start).
        let planner = PosePlanner::from_scenario(&s);
        let Some((clearance, pose, _rpy)) = planner.best_clearance_at(start) else {
            continue;
        };
        if opts.require_arm_reachable
            && !(clearance > s.arm_safe_distance && planner.cell_reachable(target))
        {
            continue;
        }
        s.arm.beta0_deg = pose.map(f64::to_degrees);
        if s.validate().is_err() {
            continue;
        }
        let world = GridWorld::new(&s)?;
        if world.shortest_path().is_none() {
            continue;
        }
        return Ok(s);
    }
    Err(Error::argument(
        "seed",
        seed,
        format!(
            "no scenario meeting the guarantees found in {} attempts (density {})",
            opts.max_attempts, opts.density
        ),
    ))
}
