//! Tabular Q-learning of the terminal's path (eqs. 6-8), and Q-table files.
//!
//! Entry points:
//! - [`train`] — learn a [`QTable`] on a [`GridWorld`] with [`Learning`]; returns the
//!   learned path, per-episode statistics and the converged episode ([`TrainResult`]).
//! - [`greedy_path`] — the learned path (`place`, eq. 8) of a Q-table.
//! - [`q_update`] — one update of eq. 6 (the learner uses the same arithmetic).
//! - [`QTable::save`] / [`QTable::load`] — atomic Q-table files, checked against the world.
//! - [`QTable::zeros_with`] / [`QTable::precision`] / [`QTable::bytes_per_state`] — tables of
//!   f64 (the default) or f32 values ([`QPrecision`]); values are read and written as f64.
//!
//! ```
//! use sixaxis_core::grid::GridWorld;
//! use sixaxis_core::qlearning::{train, Learning};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let world = GridWorld::new(&s).unwrap();
//! let mut opts = Learning::from_scenario(&s); // the paper's 10,000 episodes ...
//! opts.episodes = 200; // ... fewer here
//! let r = train(&world, &opts, None, None).unwrap();
//! assert_eq!(r.steps_per_episode.len(), 200);
//! ```
//!
//! # Choices where the SPEC is silent
//!
//! - **Episodes are counted from 0**: episode `eta` in `0..episodes` explores with
//!   `epsilon = epsilon_start * (1 - eta / M)` for `eta <= M`, else 0
//!   (`M = epsilon_decay_episodes`; `M = 0` means no exploration at all). With the paper's
//!   M = 9900 and 10,000 episodes, episodes 9900..=9999 are purely greedy.
//! - **Action selection** per step: if `epsilon > 0`, draw `k = next_u32()` and explore if
//!   `k < ceil(epsilon * 2^32)` (that is `u < epsilon` for `u = k / 2^32` uniform in
//!   [0, 1)): then take an action uniformly from all six (`random_range(0..6u32)`). Otherwise take the greedy action;
//!   when several actions share the maximal Q-value, one of them is drawn uniformly
//!   (`random_range(0..ties)` over the tied actions in index order; a draw is made only
//!   when there is a tie). All draws come from one
//!   `ChaCha8Rng::seed_from_u64(seed)` per call of [`train`], in this order, so a run is
//!   fully determined by (world, options, initial Q-table).
//! - **Episode end**: on reaching the target (terminal state: the update does not
//!   bootstrap, `Q += alpha (R - Q)`), or after `max_steps_per_episode` steps (truncation:
//!   the last update bootstraps as usual).
//! - **Detour memory** (eq. 9) is reset at the start of every episode.
//! - **Greedy rollout** ([`greedy_path`], eq. 8): from the start, always the action of
//!   highest Q, ties broken by the *lowest action index* (deterministic); cells
//!   start..=target. It fails (`None`) if it does not reach the target within
//!   `max_steps_per_episode` steps or if it revisits a cell (a colliding greedy move
//!   revisits the cell it stays on).
//! - **Converged episode**: the index (from 0, of this call of [`train`]) of the first
//!   episode after whose updates the greedy path equals the greedy path after every later
//!   episode; `None` if the final greedy path fails. The path after the last episode is
//!   compared with the path after the one before, ..., and with the path of the initial
//!   Q-table for episode 0; if it never changed, the answer is 0. The learner recomputes
//!   the greedy path only after an episode whose updates changed the greedy action of a
//!   state the current rollout consults, which is exact and cheap. Late changes are
//!   usually swaps between equally short paths whose Q-values are still settling, so
//!   [`TrainResult::length_converged_episode`] also reports the first episode from which
//!   the path's length no longer changed.
//! - **`episodes_auto`** (`--episodes auto`, ours; the paper's fixed `episodes` and M stay
//!   the default): `episodes` is then a cap, and the run follows three phases.
//!   *Search*: `epsilon = epsilon_start` until the greedy path first reaches the target, after
//!   episode `e1`. *Settle*: epsilon falls linearly to 0 over the next
//!   `H = max(e1 + 1, AUTO_MIN_HORIZON)` episodes, `epsilon_start * (1 - (eta - e1) / H)`
//!   for `eta` in `e1 + 1 ..= e1 + H` (the horizon grows with the time the world needed to
//!   be solved, not a fixed M). *Confirm*: purely greedy; the run stops after the first
//!   episode `eta >= e1 + H` after which the greedy path reaches the target and has not
//!   changed for `H` episodes (tracked exactly after every episode). `epsilon_decay_episodes`
//!   is not used. Hitting the cap ends the run like a fixed run of that length.
//! - **`initial_q = "distance"`** (`learning.initial_q`, `--initial-q distance`; ours, the
//!   paper's Q = 0 stays the default): with no table given, Q starts at
//!   [`distance_bound_table`], an optimistic bound of the return of each move. A move costs
//!   at least `1 + manhattan(next, target)` moves to the target in a 6-connected grid, and
//!   eq. 10 can pay at most `r_e (d_o - L_j)` at the `j`-th of them, where `L_j` is a lower
//!   bound of the distance left ([`distance_bound_values`]). The bound is at least the best
//!   return of every collision-free path (tested), so greedy learning from it behaves like
//!   A*/LRTA*: it follows moves that could still be optimal and lowers them when the world
//!   says otherwise, instead of trying every action of every state as Q = 0 with rewards
//!   of -p does. A colliding move counts as an ordinary step that stays put (its first
//!   reward is taken as `-p`, not `-P`), so the start table never prefers a wall. Caveat:
//!   with eq. 9 off and `P < p`, a state more than 9 moves from the target (at the
//!   defaults) is worth more colliding forever (`-P / (1 - gamma)` = -80,000) than any
//!   path; no start table changes that optimum, so no path is learned there.
//! - **`q_precision = "f32"`** (`learning.q_precision`, `--q-precision f32`; ours, the
//!   paper's f64 stays the default): the table stores f32 values, 24 bytes per state
//!   instead of 48 ([`QTable::bytes_per_state`]). Nothing else changes: each update of
//!   eq. 6 reads the stored values as f64, computes in f64 exactly as the f64 learner does,
//!   and stores the result rounded to the nearest f32; greedy choices and ties compare the
//!   stored values. The `"distance"` start table is computed in f64 and stored rounded. An
//!   f32 run is deterministic like an f64 run, but not equal to it: rounding makes
//!   different values tie or order differently, so the random stream and the learned path
//!   may differ (measured in docs/PERFORMANCE.md). The learner is generic over the value
//!   type and dispatched once per call of [`train`]; with f64 it is the identity and the
//!   results are bit for bit those of the f64-only learner.
//! - **Resuming** ([`train`] with `initial_q`): the run starts from that table but is
//!   otherwise a fresh run: its generator is seeded with `opts.seed`, episodes (and so the
//!   epsilon schedule) count from 0 again, and the converged episode is an index of this
//!   run. Pass a seed different from the first run's to avoid replaying its random stream,
//!   and e.g. `epsilon_start = 0` to continue purely greedily. A table whose precision is
//!   not `opts.q_precision` is converted first ([`QTable::into_precision`]: exact from f32
//!   to f64, rounded to the nearest f32 the other way, an error for a value beyond the f32
//!   range), so the result always has the run's precision.
//!
//! # Q-table file format (version 1)
//!
//! ```text
//! SIXAXIS-QTABLE 1\n
//! {JSON header}\n
//! num_states * 6 values (f64 or f32, as `values` says), little-endian, row-major (state, action)
//! ```
//! The header records `num_states`, `actions` (6), `values` (`"f64"` or `"f32"`; a file
//! without it, written before f32 tables existed, holds f64), `bounds`, `start`, `target`,
//! `blocked_cells` (count), `fingerprint` (FNV-1a 64 of bounds, blocked cells and target,
//! hex), `values_checksum` (FNV-1a 64 of the value bytes, hex) and `layout` (the same in
//! words). Values are stored as raw bits, so a round trip is exact in either precision.
//! [`QTable::load`] returns the table in the file's precision ([`train`] converts it to the
//! run's). It answers [`Error::QTableMismatch`] when
//! bounds, target or blocked cells differ from the world's; a file that is not a Q-table,
//! is truncated or fails its checksum gives an [`Error::Io`] of kind `InvalidData`.
//! Saving writes a temporary file in the same directory and renames it over the target;
//! on any error the temporary file is removed.

use std::path::Path;
use std::time::Instant;

use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::grid::{Fnv, GridWorld, Transition, NUM_ACTIONS};
use crate::scenario::{Assist, Bounds, Cell, InitialQ, QPrecision, Scenario};

/// The options of [`train`] are the scenario's `learning` section, [`Learning`] (declared
/// once in [`crate::scenario`]; requests override it through [`crate::request`]).
pub use crate::scenario::{Learning, AUTO_EPISODE_CAP};

/// Shortest settle horizon of `episodes_auto`, episodes.
pub const AUTO_MIN_HORIZON: u32 = 100;

/// Q-values: `num_states` rows of six actions, stored as f64 (the default) or f32
/// ([`QPrecision`]); every accessor reads and writes them as f64.
#[derive(Debug, Clone, PartialEq)]
pub struct QTable {
    rows: Rows,
}

/// The rows of a [`QTable`], in its precision.
#[derive(Debug, Clone, PartialEq)]
enum Rows {
    F64(Vec<[f64; NUM_ACTIONS]>),
    F32(Vec<[f32; NUM_ACTIONS]>),
}

/// `body` with `$r` bound to the rows of `$rows`, whatever their value type.
macro_rules! with_rows {
    ($rows:expr, $r:ident => $body:expr) => {
        match $rows {
            Rows::F64($r) => $body,
            Rows::F32($r) => $body,
        }
    };
}

/// A type Q-values are stored in. Arithmetic is always done in f64: a value is read with
/// [`QValue::to_f64`] and an update's result stored with [`QValue::from_f64`] (the identity
/// for f64, rounding to nearest for f32).
trait QValue: Copy + PartialOrd + std::fmt::Debug {
    const PRECISION: QPrecision;
    const ZERO: Self;
    fn from_f64(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn is_finite(self) -> bool;
    /// Append the little-endian bytes.
    fn write_le(self, out: &mut Vec<u8>);
    /// From `PRECISION.value_bytes()` little-endian bytes.
    fn read_le(bytes: &[u8]) -> Self;
    fn wrap(rows: Vec<[Self; NUM_ACTIONS]>) -> Rows;
}

/// [`QValue`] for a float type `$t` stored as `Rows::$variant`.
macro_rules! impl_q_value {
    ($t:ty, $variant:ident) => {
        impl QValue for $t {
            const PRECISION: QPrecision = QPrecision::$variant;
            const ZERO: Self = 0.0;
            #[inline(always)]
            fn from_f64(v: f64) -> Self {
                // The identity for f64; rounding to nearest for f32.
                v as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            fn write_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn read_le(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(bytes.try_into().expect("one value's bytes"))
            }
            fn wrap(rows: Vec<[Self; NUM_ACTIONS]>) -> Rows {
                Rows::$variant(rows)
            }
        }
    };
}

impl_q_value!(f64, F64);
impl_q_value!(f32, F32);

/// Rows of six from flat row-major values (`num_states * 6` of them).
fn rows_of<V: QValue>(num_states: usize, values: &[V]) -> Result<Vec<[V; NUM_ACTIONS]>> {
    if values.len() != num_states * NUM_ACTIONS {
        return Err(Error::argument(
            "values",
            format!("{} values", values.len()),
            format!("expected num_states * 6 = {}", num_states * NUM_ACTIONS),
        ));
    }
    Ok(values
        .chunks_exact(NUM_ACTIONS)
        .map(|c| c.try_into().expect("chunks of six"))
        .collect())
}

/// Index of the largest value, lowest index on ties.
#[inline(always)]
fn argmax_lowest<V: QValue>(row: &[V; NUM_ACTIONS]) -> usize {
    max_mask(row).trailing_zeros() as usize
}

/// Bit `a` set for every action of maximal value (branch-free).
#[inline(always)]
fn max_mask<V: QValue>(row: &[V; NUM_ACTIONS]) -> u32 {
    mask_of(row, row_max(row))
}

/// Bit `a` set for every action whose value equals `m`.
#[inline(always)]
fn mask_of<V: QValue>(row: &[V; NUM_ACTIONS], m: V) -> u32 {
    let mut mask = 0u32;
    for (i, &v) in row.iter().enumerate() {
        mask |= ((v == m) as u32) << i;
    }
    mask
}

/// Index of the `n`-th set bit (from 0, lowest first) of `mask`.
#[inline]
fn nth_set_bit(mut mask: u32, n: u32) -> usize {
    for _ in 0..n {
        mask &= mask - 1;
    }
    mask.trailing_zeros() as usize
}

#[inline(always)]
fn row_max<V: QValue>(row: &[V; NUM_ACTIONS]) -> V {
    // A tree (depth 3, not a chain of 5): the value is the same, the latency shorter.
    let a = if row[1] > row[0] { row[1] } else { row[0] };
    let b = if row[3] > row[2] { row[3] } else { row[2] };
    let c = if row[5] > row[4] { row[5] } else { row[4] };
    let ab = if b > a { b } else { a };
    if c > ab {
        c
    } else {
        ab
    }
}

/// Eq. 6: `old + alpha * (reward + gamma * bootstrap - old)`.
#[inline(always)]
fn updated(old: f64, reward: f64, bootstrap: f64, alpha: f64, gamma: f64) -> f64 {
    old + alpha * (reward + gamma * bootstrap - old)
}

/// The rows of `values`, converted to `V`; an error names the first value that does not
/// fit `V` (finite f64s beyond the f32 range become infinite).
fn converted<V: QValue, W: QValue>(values: &[[W; NUM_ACTIONS]]) -> Result<Vec<[V; NUM_ACTIONS]>> {
    let rows: Vec<[V; NUM_ACTIONS]> = values
        .iter()
        .map(|row| row.map(|v| V::from_f64(v.to_f64())))
        .collect();
    for (s, row) in rows.iter().enumerate() {
        if let Some(a) = row.iter().position(|v| !v.is_finite()) {
            return Err(Error::argument(
                "q_precision",
                V::PRECISION.name(),
                format!(
                    "Q-value {} (state {s}, action {a}) does not fit in {}",
                    values[s][a].to_f64(),
                    V::PRECISION.name()
                ),
            ));
        }
    }
    Ok(rows)
}

impl QTable {
    /// All zeros, f64.
    pub fn zeros(num_states: usize) -> Self {
        QTable::zeros_with(num_states, QPrecision::F64)
    }

    /// All zeros, in `precision`.
    pub fn zeros_with(num_states: usize, precision: QPrecision) -> Self {
        let rows = match precision {
            QPrecision::F64 => Rows::F64(vec![[0.0; NUM_ACTIONS]; num_states]),
            QPrecision::F32 => Rows::F32(vec![[0.0; NUM_ACTIONS]; num_states]),
        };
        QTable { rows }
    }

    /// An f64 table from flat row-major values (`num_states * 6` of them).
    pub fn from_values(num_states: usize, values: Vec<f64>) -> Result<Self> {
        Ok(QTable {
            rows: Rows::F64(rows_of(num_states, &values)?),
        })
    }

    /// An f32 table from flat row-major values (`num_states * 6` of them).
    pub fn from_values_f32(num_states: usize, values: Vec<f32>) -> Result<Self> {
        Ok(QTable {
            rows: Rows::F32(rows_of(num_states, &values)?),
        })
    }

    /// The same values in `precision`: exact from f32 to f64, rounded to the nearest f32
    /// the other way (an error names a value beyond the f32 range). A no-op if the table
    /// already has that precision.
    pub fn into_precision(self, precision: QPrecision) -> Result<Self> {
        let rows = match (self.rows, precision) {
            (Rows::F64(r), QPrecision::F32) => Rows::F32(converted(&r)?),
            (Rows::F32(r), QPrecision::F64) => Rows::F64(converted(&r)?),
            (rows, _) => rows,
        };
        Ok(QTable { rows })
    }

    /// The type the values are stored in.
    pub fn precision(&self) -> QPrecision {
        match self.rows {
            Rows::F64(_) => QPrecision::F64,
            Rows::F32(_) => QPrecision::F32,
        }
    }

    /// Bytes of Q-values per state: 48 for f64, 24 for f32.
    pub fn bytes_per_state(&self) -> usize {
        NUM_ACTIONS * self.precision().value_bytes()
    }

    /// Number of states.
    pub fn num_states(&self) -> usize {
        with_rows!(&self.rows, r => r.len())
    }

    /// All values as f64 (exact for both precisions), row-major (state, action); a copy.
    pub fn values(&self) -> Vec<f64> {
        with_rows!(&self.rows, r => r.as_flattened().iter().map(|v| v.to_f64()).collect())
    }

    /// The values of an f64 table, row-major, without a copy (`None` for f32).
    pub fn values_f64(&self) -> Option<&[f64]> {
        match &self.rows {
            Rows::F64(r) => Some(r.as_flattened()),
            Rows::F32(_) => None,
        }
    }

    /// The values of an f32 table, row-major, without a copy (`None` for f64).
    pub fn values_f32(&self) -> Option<&[f32]> {
        match &self.rows {
            Rows::F32(r) => Some(r.as_flattened()),
            Rows::F64(_) => None,
        }
    }

    /// Q(s, a).
    #[inline]
    pub fn get(&self, s: usize, a: usize) -> f64 {
        with_rows!(&self.rows, r => r[s][a].to_f64())
    }

    /// Set Q(s, a) (rounded to the nearest f32 in an f32 table).
    #[inline]
    pub fn set(&mut self, s: usize, a: usize, value: f64) {
        with_rows!(&mut self.rows, r => r[s][a] = QValue::from_f64(value))
    }

    /// The six values of a state.
    #[inline]
    pub fn row(&self, s: usize) -> [f64; NUM_ACTIONS] {
        with_rows!(&self.rows, r => r[s].map(QValue::to_f64))
    }

    /// `max_a Q(s, a)`.
    #[inline]
    pub fn max_value(&self, s: usize) -> f64 {
        with_rows!(&self.rows, r => row_max(&r[s]).to_f64())
    }

    /// The greedy action of a state, ties broken by the lowest action index.
    #[inline]
    pub fn greedy_action(&self, s: usize) -> usize {
        with_rows!(&self.rows, r => argmax_lowest(&r[s]))
    }

    /// Write the table to `path` atomically (temporary file in the same directory, then
    /// rename), with a header that ties it to `world` (see the module docs for the format).
    pub fn save(&self, path: &Path, world: &GridWorld) -> Result<()> {
        if self.num_states() != world.num_states() {
            return Err(Error::QTableMismatch(format!(
                "table has {} states, world has {}",
                self.num_states(),
                world.num_states()
            )));
        }
        let precision = self.precision();
        let mut body = Vec::with_capacity(self.num_states() * self.bytes_per_state());
        with_rows!(&self.rows, r => r.as_flattened().iter().for_each(|v| v.write_le(&mut body)));
        let mut ck = Fnv::new();
        ck.write(&body);
        let header = FileHeader {
            format: FORMAT_NAME.to_string(),
            version: FORMAT_VERSION,
            num_states: self.num_states(),
            actions: NUM_ACTIONS,
            values: Some(precision.name().to_string()),
            bounds: world.bounds(),
            start: world.cell_of(world.start()),
            target: world.cell_of(world.target()),
            blocked_cells: world.num_blocked(),
            fingerprint: format!("{:016x}", world.fingerprint()),
            values_checksum: format!("{:016x}", ck.finish()),
            layout: format!(
                "{} little-endian, row-major (state, action); actions +x -x +y -y +z -z",
                precision.name()
            ),
        };
        let mut bytes = format!("{MAGIC}\n").into_bytes();
        bytes.extend_from_slice(
            serde_json::to_string(&header)
                .expect("a header always serialises")
                .as_bytes(),
        );
        bytes.push(b'\n');
        bytes.extend_from_slice(&body);
        crate::io::write_atomic(path, &bytes)
    }

    /// Read a table written by [`QTable::save`] and check it fits `world`
    /// ([`Error::QTableMismatch`] if bounds, target or blocked cells differ).
    pub fn load(path: &Path, world: &GridWorld) -> Result<QTable> {
        // A table of `world` is its values (at most 8 bytes each, f64) plus a header of a
        // few hundred bytes: reading no more than that keeps `/dev/zero` or a huge stray
        // file from exhausting memory.
        let largest = QPrecision::F64.value_bytes();
        let max_bytes = (world.num_states() * NUM_ACTIONS * largest + MAX_HEADER_BYTES) as u64;
        let bytes = crate::io::read_bounded(path, max_bytes)?;
        QTable::from_file_bytes(&bytes, world, path)
    }

    /// Parse the bytes of a Q-table file (as [`QTable::save`] writes them) and check they
    /// fit `world`; `path` only names the source in errors. Every malformed input (truncated,
    /// bit-flipped, another world's) is an error, never a panic.
    pub fn from_file_bytes(bytes: &[u8], world: &GridWorld, path: &Path) -> Result<QTable> {
        let bad = |why: String| {
            Error::io(
                path,
                std::io::Error::new(std::io::ErrorKind::InvalidData, why),
            )
        };
        let magic = format!("{MAGIC}\n");
        if !bytes.starts_with(magic.as_bytes()) {
            return Err(bad(format!(
                "not a SixAxisAvoid Q-table file (expected first line `{MAGIC}`)"
            )));
        }
        let rest = &bytes[magic.len()..];
        let nl = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| bad("Q-table header is not terminated".to_string()))?;
        let header: FileHeader = serde_json::from_slice(&rest[..nl])
            .map_err(|e| bad(format!("Q-table header is invalid: {e}")))?;
        if header.format != FORMAT_NAME || header.version != FORMAT_VERSION {
            return Err(bad(format!(
                "unsupported Q-table format {} version {}",
                header.format, header.version
            )));
        }
        // Files written before f32 tables existed have no `values` field: f64.
        let precision = match header.values.as_deref() {
            None => QPrecision::F64,
            Some(name) => QPrecision::from_name("values", name)
                .map_err(|_| bad(format!("Q-table header has an unknown value type: {name}")))?,
        };
        if header.actions != NUM_ACTIONS {
            return Err(Error::QTableMismatch(format!(
                "file has {} actions per state, expected {NUM_ACTIONS}",
                header.actions
            )));
        }
        let wb = world.bounds();
        if header.bounds != wb || header.num_states != world.num_states() {
            return Err(Error::QTableMismatch(format!(
                "bounds differ: file min {:?} max {:?} ({} states), world min {:?} max {:?} ({} states)",
                header.bounds.min,
                header.bounds.max,
                header.num_states,
                wb.min,
                wb.max,
                world.num_states()
            )));
        }
        let wt = world.cell_of(world.target());
        if header.target != wt {
            return Err(Error::QTableMismatch(format!(
                "target differs: file {:?}, world {:?}",
                header.target, wt
            )));
        }
        let wf = format!("{:016x}", world.fingerprint());
        if header.fingerprint != wf {
            return Err(Error::QTableMismatch(format!(
                "obstacles differ: file has {} blocked cells (fingerprint {}), world has {} (fingerprint {wf})",
                header.blocked_cells,
                header.fingerprint,
                world.num_blocked()
            )));
        }
        let body = &rest[nl + 1..];
        let expected = header.num_states * NUM_ACTIONS * precision.value_bytes();
        if body.len() != expected {
            return Err(bad(format!(
                "Q-table values have {} bytes, expected {expected} ({} {} values)",
                body.len(),
                header.num_states * NUM_ACTIONS,
                precision.name()
            )));
        }
        let mut ck = Fnv::new();
        ck.write(body);
        if format!("{:016x}", ck.finish()) != header.values_checksum {
            return Err(bad("Q-table values fail their checksum".to_string()));
        }
        let rows = match precision {
            QPrecision::F64 => parse_rows::<f64>(header.num_states, body),
            QPrecision::F32 => parse_rows::<f32>(header.num_states, body),
        };
        rows.map(|rows| QTable { rows }).map_err(|(i, v)| {
            bad(format!(
                "Q-table value {i} (state {}, action {}) is {v}, not a finite number",
                i / NUM_ACTIONS,
                i % NUM_ACTIONS,
            ))
        })
    }
}

/// The rows of a file's value bytes (`num_states * 6 * V::BYTES` of them, checked), or the
/// index and value of the first value that is not finite.
fn parse_rows<V: QValue>(
    num_states: usize,
    body: &[u8],
) -> std::result::Result<Rows, (usize, f64)> {
    let values: Vec<V> = body
        .chunks_exact(V::PRECISION.value_bytes())
        .map(V::read_le)
        .collect();
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err((i, values[i].to_f64()));
    }
    Ok(V::wrap(
        rows_of(num_states, &values).expect("the body length was checked"),
    ))
}

const MAGIC: &str = "SIXAXIS-QTABLE 1";
/// Bound on a Q-table file's magic line and JSON header, bytes.
const MAX_HEADER_BYTES: usize = 64 * 1024;
const FORMAT_NAME: &str = "sixaxis-qtable";
const FORMAT_VERSION: u32 = 1;

#[derive(Debug, Serialize, Deserialize)]
struct FileHeader {
    format: String,
    version: u32,
    num_states: usize,
    actions: usize,
    /// `"f64"` or `"f32"`; absent (f64) in files written before f32 tables existed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    values: Option<String>,
    bounds: Bounds,
    start: Cell,
    target: Cell,
    blocked_cells: usize,
    fingerprint: String,
    values_checksum: String,
    layout: String,
}

/// One update of eq. 6 for the step `state --action--> t`: bootstraps from
/// `max_a' Q(t.next, a')` unless `t.reached` (the target is terminal). Returns the new
/// Q(state, action) as stored (rounded to the nearest f32 in an f32 table). The learner
/// uses exactly this arithmetic.
pub fn q_update(
    q: &mut QTable,
    state: usize,
    action: usize,
    t: &Transition,
    alpha: f64,
    gamma: f64,
) -> f64 {
    let bootstrap = if t.reached { 0.0 } else { q.max_value(t.next) };
    let v = updated(q.get(state, action), t.reward, bootstrap, alpha, gamma);
    q.set(state, action, v);
    q.get(state, action)
}

/// The `"distance"` initial Q-table (`learning.initial_q`, ours; see the module docs):
/// `Q0(s, a) = R1(s, a) + gamma * V0(next(s, a))`, where `R1` is the first step's reward
/// with the move counted as an ordinary step (`-p`, or `+r` when it reaches the target,
/// plus eq. 10 when on) and `V0(n)` bounds from above the return of every collision-free
/// path from `n` to the target ([`distance_bound_values`]). The target's row is 0. The
/// table has `opts.q_precision` (values computed in f64, then stored).
pub fn distance_bound_table(world: &GridWorld, opts: &Learning) -> QTable {
    let rows = match opts.q_precision {
        QPrecision::F64 => Rows::F64(distance_bound_rows(world, opts)),
        QPrecision::F32 => Rows::F32(distance_bound_rows(world, opts)),
    };
    QTable { rows }
}

fn distance_bound_rows<V: QValue>(world: &GridWorld, opts: &Learning) -> Vec<[V; NUM_ACTIONS]> {
    let v0 = distance_bound_values(world, opts);
    let rw = world.rewards();
    let r_e = if opts.assist_distance {
        rw.distance_reward
    } else {
        0.0
    };
    let d_o = world.start_distance_cells();
    let target = world.target();
    world
        .transitions()
        .iter()
        .enumerate()
        .map(|(s, next)| {
            if s == target {
                return [V::ZERO; NUM_ACTIONS];
            }
            next.map(|n| {
                let n = n as usize;
                let eq10 = r_e * (d_o - world.distance_to_target_cells(n));
                V::from_f64(if n == target {
                    rw.target_reward + eq10
                } else {
                    -rw.step_penalty + eq10 + opts.gamma * v0[n]
                })
            })
        })
        .collect()
}

/// Per state `n`, an upper bound `V0(n)` of the discounted return (eqs. 5 and, when on, 10)
/// of any collision-free path from `n` to the target (0 at the target): with
/// `k = manhattan(n, target)` moves, at least `k` are needed, and after `j` moves the
/// distance to the target is at least `L_j = max(d_t(n) - j, (k - j) / sqrt 3, 0)` cells,
/// so `V0(n) = sum_{j=1}^{k-1} gamma^(j-1) (-p + r_e (d_o - L_j)) + gamma^(k-1) (r + r_e d_o)`.
/// While every step's reward is negative (`r_e d_o < p`), a longer path only lowers this
/// sum, so the bound holds for paths of every length. Exact on a straight free path.
pub fn distance_bound_values(world: &GridWorld, opts: &Learning) -> Vec<f64> {
    let rw = world.rewards();
    let (p, r, gamma) = (rw.step_penalty, rw.target_reward, opts.gamma);
    let r_e = if opts.assist_distance {
        rw.distance_reward
    } else {
        0.0
    };
    let d_o = world.start_distance_cells();
    let tc = world.cell_of(world.target());
    let inv_sqrt3 = 1.0 / 3f64.sqrt();
    (0..world.num_states())
        .map(|n| {
            let c = world.cell_of(n);
            let k: i64 = (0..3).map(|i| (c[i] - tc[i]).abs() as i64).sum();
            if k == 0 {
                return 0.0;
            }
            let d_n = world.distance_to_target_cells(n);
            let mut sum = 0.0;
            let mut disc = 1.0;
            for j in 1..k {
                let l = (d_n - j as f64).max((k - j) as f64 * inv_sqrt3).max(0.0);
                sum += disc * (-p + r_e * (d_o - l));
                disc *= gamma;
            }
            sum + disc * (r + r_e * d_o)
        })
        .collect()
}

/// What [`train`] returns.
#[derive(Debug, Clone, Serialize)]
pub struct TrainResult {
    /// The learned path (greedy rollout, eq. 8), start..=target; `None` if it fails.
    pub path: Option<Vec<Cell>>,
    /// Steps of each episode.
    pub steps_per_episode: Vec<u32>,
    /// Whether each episode reached the target.
    pub reached_per_episode: Vec<bool>,
    /// First episode (from 0) from which the greedy path no longer changed; `None` if the
    /// final path fails.
    pub converged_episode: Option<u32>,
    /// First episode (from 0) from which the greedy path's *length* no longer changed
    /// (later changes, if any, swap equally long paths); `None` if the final path fails.
    pub length_converged_episode: Option<u32>,
    /// Environment steps over all episodes.
    pub total_steps: u64,
    /// Wall time of the call, seconds.
    pub wall_time_s: f64,
    /// The learned Q-table.
    #[serde(skip)]
    pub q: QTable,
}

/// What a training run reports: the options it ran with and what it learned, the one
/// serialisation of a run (the JSON of `sixaxis train` and Python's `TrainResult.to_dict()`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// The scenario's name.
    pub scenario: String,
    /// Seed of the run's generator.
    pub seed: u64,
    /// Episodes asked for (the cap with `episodes_auto`).
    pub episodes: u32,
    /// Whether the run stopped when the greedy path settled (`episodes = "auto"`).
    pub episodes_auto: bool,
    /// How the Q-table started.
    pub initial_q: InitialQ,
    /// The type of the Q-values.
    pub q_precision: QPrecision,
    /// Size of the Q-table's values, bytes.
    pub q_table_bytes: usize,
    /// Episodes run.
    pub episodes_run: usize,
    /// Environment steps up to and including the converged episode; `None` without one.
    pub steps_to_converged: Option<u64>,
    /// The assisted strategies of the run (eqs. 9 and 10).
    pub assist: Assist,
    /// Whether the learned path reaches the target.
    pub reached: bool,
    /// The learned path, start..=target (cells); `None` if it fails.
    pub path: Option<Vec<Cell>>,
    /// Moves of the learned path.
    pub path_length: Option<usize>,
    /// Moves of the shortest (BFS) path; `None` if the target is unreachable.
    pub shortest_path_length: Option<usize>,
    /// See [`TrainResult::converged_episode`].
    pub converged_episode: Option<u32>,
    /// See [`TrainResult::length_converged_episode`].
    pub length_converged_episode: Option<u32>,
    /// Environment steps over all episodes.
    pub total_steps: u64,
    /// Wall time of the run, s.
    pub wall_time_s: f64,
    /// `total_steps / wall_time_s`, environment steps per second (0 for no time).
    pub steps_per_second: f64,
    /// Steps of each episode (left out of a report without curves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps_per_episode: Option<Vec<u32>>,
    /// Whether each episode reached the target (left out of a report without curves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reached_per_episode: Option<Vec<bool>>,
}

impl TrainReport {
    /// The report of run `r` with options `opts` on `world` (of scenario `s`); `curves`
    /// keeps the per-episode figures.
    pub fn new(
        s: &Scenario,
        world: &GridWorld,
        opts: &Learning,
        r: &TrainResult,
        curves: bool,
    ) -> Self {
        TrainReport {
            scenario: s.name.clone(),
            seed: opts.seed,
            episodes: opts.episodes,
            episodes_auto: opts.episodes_auto,
            initial_q: opts.initial_q,
            q_precision: opts.q_precision,
            q_table_bytes: r.q.num_states() * r.q.bytes_per_state(),
            episodes_run: r.steps_per_episode.len(),
            steps_to_converged: r.converged_episode.map(|e| {
                r.steps_per_episode[..=e as usize]
                    .iter()
                    .map(|&k| k as u64)
                    .sum()
            }),
            assist: opts.assist(),
            reached: r.path.is_some(),
            path: r.path.clone(),
            path_length: r.path.as_ref().map(|p| p.len() - 1),
            shortest_path_length: world.shortest_path().map(|p| p.len() - 1),
            converged_episode: r.converged_episode,
            length_converged_episode: r.length_converged_episode,
            total_steps: r.total_steps,
            wall_time_s: r.wall_time_s,
            steps_per_second: if r.wall_time_s > 0.0 {
                r.total_steps as f64 / r.wall_time_s
            } else {
                0.0
            },
            steps_per_episode: curves.then(|| r.steps_per_episode.clone()),
            reached_per_episode: curves.then(|| r.reached_per_episode.clone()),
        }
    }
}

/// Greedy rollout from the start (ties: lowest action index), writing the visited states
/// into `out` and stamping each with `gen` in `stamp` (the visited set) and its greedy
/// action in `act`. Returns whether it reached the target.
fn rollout<V: QValue>(
    world: &GridWorld,
    q: &[[V; NUM_ACTIONS]],
    max_steps: u32,
    stamp: &mut [u32],
    act: &mut [u8],
    gen: u32,
    out: &mut Vec<u32>,
) -> bool {
    let next = world.transitions();
    let target = world.target();
    out.clear();
    let mut cur = world.start();
    out.push(cur as u32);
    stamp[cur] = gen;
    for _ in 0..max_steps {
        if cur == target {
            return true;
        }
        let a = argmax_lowest(&q[cur]);
        act[cur] = a as u8;
        let n = next[cur][a] as usize;
        if stamp[n] == gen {
            return false;
        }
        stamp[n] = gen;
        act[n] = argmax_lowest(&q[n]) as u8;
        out.push(n as u32);
        cur = n;
    }
    cur == target
}

/// The learned path (eq. 8) of a Q-table: greedy rollout from the world's start, ties
/// broken by the lowest action index, cells start..=target; `None` if the target is not
/// reached within `max_steps` steps or a cell is revisited.
pub fn greedy_path(world: &GridWorld, q: &QTable, max_steps: u32) -> Option<Vec<Cell>> {
    if q.num_states() != world.num_states() {
        return None;
    }
    let n = world.num_states();
    let mut stamp = vec![0u32; n];
    let mut act = vec![0u8; n];
    let mut out = Vec::new();
    if with_rows!(&q.rows, r => rollout(world, r, max_steps, &mut stamp, &mut act, 1, &mut out)) {
        Some(out.iter().map(|&s| world.cell_of(s as usize)).collect())
    } else {
        None
    }
}

/// Learn a Q-table on `world` (eqs. 6-7), starting from `initial_q` or zeros. `progress`
/// is called with the number of episodes done, at most about 100 times. See the module
/// docs for the exact semantics; the result is a pure function of the arguments (but
/// `wall_time_s`).
pub fn train(
    world: &GridWorld,
    opts: &Learning,
    initial_q: Option<QTable>,
    progress: Option<&dyn Fn(u32)>,
) -> Result<TrainResult> {
    train_impl(world, opts, initial_q, progress, false)
}

/// [`train`]; with `rollout_every_episode` the greedy path is recomputed after every
/// episode (the reference for the incremental bookkeeping, for tests).
fn train_impl(
    world: &GridWorld,
    opts: &Learning,
    initial_q: Option<QTable>,
    progress: Option<&dyn Fn(u32)>,
    rollout_every_episode: bool,
) -> Result<TrainResult> {
    let started = Instant::now();
    opts.validate()?;
    let n = world.num_states();
    let q = match initial_q {
        Some(q) if q.num_states() != n => {
            return Err(Error::QTableMismatch(format!(
                "initial Q-table has {} states, world has {n}",
                q.num_states()
            )))
        }
        // A table of the other precision is converted (see the module docs).
        Some(q) => q.into_precision(opts.q_precision)?,
        None => match opts.initial_q {
            InitialQ::Zero => QTable::zeros_with(n, opts.q_precision),
            InitialQ::Distance => distance_bound_table(world, opts),
        },
    };
    // One dispatch on the value type per run; the loop itself is generic.
    Ok(
        with_rows!(q.rows, rows => learn(world, opts, rows, progress, rollout_every_episode, started)),
    )
}

/// The episodes of [`train_impl`], learning on `rows` (the run's table); `started` is when
/// the call began (for `wall_time_s`).
fn learn<V: QValue>(
    world: &GridWorld,
    opts: &Learning,
    mut rows: Vec<[V; NUM_ACTIONS]>,
    progress: Option<&dyn Fn(u32)>,
    rollout_every_episode: bool,
    started: Instant,
) -> TrainResult {
    let n = world.num_states();
    let qr: &mut [[V; NUM_ACTIONS]] = &mut rows;
    // Rewards, computed exactly as `GridWorld::step` does: eq. 5 by kind of move
    // (plain, collision, reaching), plus eq. 10 by new state, plus eq. 9.
    let assist = opts.assist();
    let rw = world.rewards();
    let eq5 = [-rw.step_penalty, -rw.collision_penalty, rw.target_reward];
    let distance = assist.distance;
    let eq10: Vec<f64> = (0..n)
        .map(|s| {
            rw.distance_reward * (world.start_distance_cells() - world.distance_to_target_cells(s))
        })
        .collect();
    let detour = assist.detour;
    let repeat_pen = -world.rewards().repeat_collision_penalty;
    let reverse_pen = -world.rewards().reverse_after_collision_penalty;

    let next = world.transitions();
    let start = world.start();
    let target = world.target();
    let (alpha, gamma) = (opts.alpha, opts.gamma);
    let max_steps = opts.max_steps_per_episode;
    let episodes = opts.episodes;
    let chunk = episodes.div_ceil(100).max(1);
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);

    // A fixed run knows its length; an auto run grows its vectors as it goes.
    let reserve = if opts.episodes_auto {
        0
    } else {
        episodes as usize
    };
    let mut steps_per_episode = Vec::with_capacity(reserve);
    let mut reached_per_episode = Vec::with_capacity(reserve);
    // episodes_auto: the episode after which the greedy path first reached the target.
    let mut first_reach: Option<u32> = None;
    let mut total_steps = 0u64;

    // Greedy-path tracking for the converged episode.
    let mut stamp = vec![0u32; n];
    let mut act = vec![0u8; n];
    let mut gen = 1u32;
    let mut path = Vec::new();
    let mut path_ok = rollout(world, qr, max_steps, &mut stamp, &mut act, gen, &mut path);
    let mut new_path = Vec::new();
    let mut last_change = 0u32;
    let mut last_length_change = 0u32;

    const NO_ACTION: usize = usize::MAX;
    for ep in 0..episodes {
        // Explore when a uniform u32 is below epsilon * 2^32 (i.e. u < epsilon for
        // u = k / 2^32 uniform in [0, 1)).
        let epsilon = if opts.episodes_auto {
            match first_reach {
                None => opts.epsilon_start,
                Some(e1) => {
                    let h = (e1 + 1).max(AUTO_MIN_HORIZON);
                    let k = ep - e1;
                    if k >= h {
                        0.0
                    } else {
                        opts.epsilon_start * (1.0 - k as f64 / h as f64)
                    }
                }
            }
        } else {
            opts.epsilon(ep)
        };
        let explore_threshold = (epsilon * 4_294_967_296.0).ceil() as u64;
        let mut s = start;
        let mut last_collided = NO_ACTION;
        let mut steps = 0u32;
        let mut reached = false;
        let mut dirty = rollout_every_episode;
        // max_a Q(s, a), carried from the previous step's bootstrap when still valid.
        let mut s_max = row_max(&qr[s]);
        while steps < max_steps {
            // Action selection (eq. 7).
            let a = if explore_threshold > 0 && (rng.next_u32() as u64) < explore_threshold {
                rng.random_range(0..NUM_ACTIONS as u32) as usize
            } else {
                let mask = mask_of(&qr[s], s_max);
                if mask & (mask - 1) == 0 {
                    mask.trailing_zeros() as usize
                } else {
                    nth_set_bit(mask, rng.random_range(0..mask.count_ones()))
                }
            };
            // Environment step (eqs. 5, 9, 10).
            let ns = next[s][a] as usize;
            let collided = ns == s;
            reached = ns == target && !collided;
            let mut reward = eq5[collided as usize + 2 * reached as usize];
            if distance {
                reward += eq10[ns];
            }
            if detour && last_collided != NO_ACTION {
                if collided {
                    reward += repeat_pen;
                } else if a ^ 1 == last_collided {
                    reward += reverse_pen;
                }
            }
            // Q-update (eq. 6), in f64 whatever the stored type.
            let next_max = row_max(&qr[ns]);
            let bootstrap = if reached { 0.0 } else { next_max.to_f64() };
            let old = qr[s][a].to_f64();
            qr[s][a] = V::from_f64(updated(old, reward, bootstrap, alpha, gamma));
            if !dirty && stamp[s] == gen && argmax_lowest(&qr[s]) != act[s] as usize {
                dirty = true;
            }
            // On a collision ns == s and its row just changed; otherwise row ns is untouched.
            s_max = if collided { row_max(&qr[s]) } else { next_max };
            last_collided = if collided { a } else { NO_ACTION };
            steps += 1;
            s = ns;
            if reached {
                break;
            }
        }
        total_steps += steps as u64;
        steps_per_episode.push(steps);
        reached_per_episode.push(reached);
        if dirty {
            if gen == u32::MAX {
                stamp.fill(0);
                gen = 0;
            }
            gen += 1;
            let ok = rollout(
                world,
                qr,
                max_steps,
                &mut stamp,
                &mut act,
                gen,
                &mut new_path,
            );
            let same = ok == path_ok && (!ok || new_path == path);
            if !same {
                last_change = ep;
                if ok != path_ok || (ok && new_path.len() != path.len()) {
                    last_length_change = ep;
                }
            }
            std::mem::swap(&mut path, &mut new_path);
            path_ok = ok;
        }
        if let Some(p) = progress {
            if (ep + 1) % chunk == 0 || ep + 1 == episodes {
                p(ep + 1);
            }
        }
        if opts.episodes_auto && path_ok {
            let e1 = *first_reach.get_or_insert(ep);
            let h = (e1 + 1).max(AUTO_MIN_HORIZON);
            if ep >= e1 + h && ep - last_change >= h {
                break;
            }
        }
    }

    let final_path = if path_ok {
        Some(path.iter().map(|&s| world.cell_of(s as usize)).collect())
    } else {
        None
    };
    TrainResult {
        path: final_path,
        steps_per_episode,
        reached_per_episode,
        converged_episode: path_ok.then_some(last_change),
        length_converged_episode: path_ok.then_some(last_length_change),
        total_steps,
        wall_time_s: started.elapsed().as_secs_f64(),
        q: QTable {
            rows: V::wrap(rows),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    #[test]
    fn epsilon_schedule() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let o = Learning::from_scenario(&s);
        assert_eq!(o.epsilon(0), 0.1);
        assert!((o.epsilon(4950) - 0.05).abs() < 1e-15);
        assert_eq!(o.epsilon(9900), 0.0);
        assert_eq!(o.epsilon(9901), 0.0);
        let o0 = Learning {
            epsilon_decay_episodes: 0,
            ..o
        };
        assert_eq!(o0.epsilon(0), 0.0);
    }

    #[test]
    fn argmax_ties_lowest() {
        assert_eq!(argmax_lowest(&[0.0; 6]), 0);
        assert_eq!(argmax_lowest(&[0.0, 1.0, 1.0, 0.0, 0.0, 0.0]), 1);
        assert_eq!(argmax_lowest(&[-1.0, -1.0, -1.0, -1.0, -1.0, -0.5]), 5);
        assert_eq!(row_max(&[-3.0, -2.0, -1.0, -4.0, -5.0, -6.0]), -1.0);
        assert_eq!(max_mask(&[0.0, 1.0, 1.0, 0.0, 1.0, 0.0]), 0b10110);
        assert_eq!(nth_set_bit(0b10110, 0), 1);
        assert_eq!(nth_set_bit(0b10110, 1), 2);
        assert_eq!(nth_set_bit(0b10110, 2), 4);
    }

    /// The optimum over collision-free moves (value iteration): the best return of any path
    /// from each state to the target, under eq. 5 and (if on) eq. 10.
    fn best_collision_free_return(world: &GridWorld, assist: Assist, gamma: f64) -> Vec<f64> {
        let n = world.num_states();
        let target = world.target();
        let mut v = vec![-1e12; n];
        v[target] = 0.0;
        loop {
            let mut change = 0.0f64;
            for s in 0..n {
                if s == target || world.is_blocked(s) {
                    continue;
                }
                let mut best = f64::NEG_INFINITY;
                for a in 0..NUM_ACTIONS {
                    let t = world.next_state(s, a);
                    if t == s {
                        continue;
                    }
                    let r = world.base_reward(s, a, assist);
                    best = best.max(if t == target { r } else { r + gamma * v[t] });
                }
                change = change.max((best - v[s]).abs());
                v[s] = best;
            }
            if change < 1e-9 {
                return v;
            }
        }
    }

    #[test]
    fn distance_bound_is_admissible_and_tight_on_free_lines() {
        for (name, assist) in [
            ("paper_simple", Assist::on()),
            ("paper_simple", Assist::off()),
            ("paper_complex", Assist::on()),
        ] {
            let s = Scenario::builtin(name).unwrap();
            let w = GridWorld::new(&s).unwrap();
            let o = Learning {
                assist_detour: assist.detour,
                assist_distance: assist.distance,
                initial_q: InitialQ::Distance,
                ..Learning::from_scenario(&s)
            };
            let v0 = distance_bound_values(&w, &o);
            let best = best_collision_free_return(&w, assist, o.gamma);
            let q0 = distance_bound_table(&w, &o);
            for st in 0..w.num_states() {
                if w.is_blocked(st) || best[st] < -1e11 {
                    continue;
                }
                assert!(
                    v0[st] >= best[st] - 1e-6,
                    "{name} {st}: {} < {}",
                    v0[st],
                    best[st]
                );
                // Q0 of a free move bounds that move's best return too.
                for a in 0..NUM_ACTIONS {
                    let t = w.next_state(st, a);
                    if st == w.target() || t == st || best[t] < -1e11 {
                        continue;
                    }
                    let r = w.base_reward(st, a, assist);
                    let qa = if t == w.target() {
                        r
                    } else {
                        r + o.gamma * best[t]
                    };
                    assert!(q0.get(st, a) >= qa - 1e-6, "{name} {st} {a}");
                }
            }
        }
        // Without obstacles the bound is exact on the axis lines through the target.
        let mut s = Scenario::builtin("paper_simple").unwrap();
        s.obstacles.clear();
        let w = GridWorld::new(&s).unwrap();
        for assist in [Assist::on(), Assist::off()] {
            let o = Learning {
                assist_detour: assist.detour,
                assist_distance: assist.distance,
                ..Learning::from_scenario(&s)
            };
            let v0 = distance_bound_values(&w, &o);
            let best = best_collision_free_return(&w, assist, o.gamma);
            let t = s.target;
            let mut on_line = 0;
            for st in 0..w.num_states() {
                let c = w.cell_of(st);
                if (0..3).filter(|&i| c[i] != t[i]).count() == 1 {
                    on_line += 1;
                    assert!(
                        (v0[st] - best[st]).abs() < 1e-6,
                        "{c:?}: {} {}",
                        v0[st],
                        best[st]
                    );
                }
            }
            assert!(on_line >= 10);
        }
    }

    #[test]
    fn initial_q_rule_and_explicit_table() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let w = GridWorld::new(&s).unwrap();
        let zero = Learning::from_scenario(&s);
        assert_eq!(
            zero.initial_q,
            InitialQ::Zero,
            "the paper's learner by default"
        );
        let dist = Learning {
            episodes: 1,
            initial_q: InitialQ::Distance,
            epsilon_start: 0.0,
            ..zero.clone()
        };
        // One purely greedy episode from the distance table changes only the rows it visits.
        let r = train(&w, &dist, None, None).unwrap();
        let q0 = distance_bound_table(&w, &dist);
        let changed = (0..w.num_states())
            .filter(|&st| r.q.row(st) != q0.row(st))
            .count();
        assert!(changed >= 1 && changed <= r.total_steps as usize);
        // An explicit table wins over the rule.
        let given = QTable::zeros(w.num_states());
        let a = train(&w, &dist, Some(given), None).unwrap();
        let b = train(
            &w,
            &Learning {
                initial_q: InitialQ::Zero,
                ..dist.clone()
            },
            None,
            None,
        )
        .unwrap();
        assert_eq!(a.q, b.q);
    }

    #[test]
    fn tracked_path_equals_fresh_rollout() {
        // The incremental converged-episode bookkeeping must agree with a fresh rollout.
        let s = Scenario::builtin("paper_simple").unwrap();
        let w = GridWorld::new(&s).unwrap();
        let mut o = Learning::from_scenario(&s);
        o.episodes = 300;
        o.epsilon_decay_episodes = 297;
        let r = train(&w, &o, None, None).unwrap();
        assert_eq!(r.path, greedy_path(&w, &r.q, o.max_steps_per_episode));
        for (name, seed, assist) in [
            ("paper_simple", 0, Assist::on()),
            ("paper_simple", 1, Assist::on()),
            ("paper_simple", 2, Assist::off()),
            ("paper_complex", 3, Assist::on()),
        ] {
            let s = Scenario::builtin(name).unwrap();
            let w = GridWorld::new(&s).unwrap();
            let mut o = Learning::from_scenario(&s);
            o.episodes = 2000;
            o.epsilon_decay_episodes = 1980;
            o.seed = seed;
            o.set_assist(assist);
            let fast = train_impl(&w, &o, None, None, false).unwrap();
            let slow = train_impl(&w, &o, None, None, true).unwrap();
            assert_eq!(fast.q, slow.q);
            assert_eq!(fast.path, slow.path);
            assert_eq!(
                fast.converged_episode, slow.converged_episode,
                "{name} {seed}"
            );
        }
    }
}
