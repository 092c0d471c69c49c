//! The terminal's grid world: states, the six actions, collisions and the rewards of
//! eqs. 5, 9 and 10.
//!
//! Entry points:
//! - [`GridWorld::new`] / [`GridWorld::with_extra_obstacles`] — build the world of a
//!   [`Scenario`] (the second adds obstacle cells, for re-planning, Algorithm 2).
//! - [`GridWorld::step`] — one move of the terminal with its [`Transition`] and reward.
//! - [`GridWorld::shortest_path`] — breadth-first shortest path over free cells.
//!
//! ```
//! use sixaxis_core::grid::{Assist, GridWorld};
//! use sixaxis_core::Scenario;
//! let world = GridWorld::new(&Scenario::builtin("paper_simple").unwrap()).unwrap();
//! assert_eq!(world.shortest_path().unwrap().len() - 1, 9); // steps (0,-2,4) -> (0,3,0)
//! let t = world.step(world.start(), 5, None, Assist::off()); // -z
//! assert_eq!((t.reward, t.collided), (-15000.0, false));
//! ```
//!
//! # Semantics (docs/SCENARIOS.md "The grid world: states, actions, collisions, rewards")
//!
//! - **States** are the cells inside `bounds` (inclusive box), numbered row-major over
//!   (x, y, z) with z fastest: `s = ((x - min_x) * ny + (y - min_y)) * nz + (z - min_z)`.
//!   Use [`GridWorld::state_of`] / [`GridWorld::cell_of`] rather than the formula.
//! - **Actions**, in this order: `0:+x 1:-x 2:+y 3:-y 4:+z 5:-z` ([`ACTIONS`]); the
//!   opposite of `a` is `a ^ 1` ([`opposite`]).
//! - **Collision**: a move collides when the new cell is out of bounds, or when its
//!   Euclidean distance (cells) to some obstacle centre is `<= terminal_safe_distance`
//!   (such cells are *blocked*). On a collision the terminal stays where it was.
//!   Boxes in mm (`obstacle_boxes_mm`) block the cells whose centre (mm) lies within
//!   `terminal_safe_distance` (mm) of the box by its rule
//!   ([`ObstacleBox::terminal_distance_mm`](crate::scenario::ObstacleBox::terminal_distance_mm)).
//!   An extra obstacle (a point Algorithm 2 adds) blocks its own cell only.
//! - **Rewards** (penalties are positive magnitudes in [`Rewards`]):
//!   - eq. 5: `+target_reward` when the move reaches the target, `-collision_penalty` when
//!     it collides, `-step_penalty` otherwise. A collision never counts as reaching the
//!     target (even if the terminal already stands on it).
//!   - eq. 9 (`Assist::detour`): if the previous step of the episode collided with action
//!     `a_prev`, this step gets an extra `-repeat_collision_penalty` if it collides again
//!     (with any action); otherwise an extra `-reverse_after_collision_penalty` if its
//!     action is the opposite of `a_prev`. The two cases are exclusive, as in the paper's
//!     case form: a reversing move that collides again pays the repeat penalty only.
//!   - eq. 10 (`Assist::distance`): `+distance_reward * (d_o - d_t)` on **every** step,
//!     the reaching step and collisions included, with `d_o = |target - start|` and
//!     `d_t = |target - new position|` (Euclidean, cells; the new position is unchanged on
//!     a collision).
//!   - The reward is computed as `(eq. 5 + eq. 10) + eq. 9`, in that order of floating
//!     point additions, here and in the learner, so both agree to the bit.
//!
//! The world precomputes the next state of every (state, action), the blocked flags and
//! `d_t` per state; the topology (bounds, blocked cells, transitions) is shared behind an
//! [`Arc`], so cloning a world is cheap.

use std::collections::VecDeque;
use std::sync::Arc;

use crate::error::{Error, Result};
pub use crate::scenario::Assist;
use crate::scenario::{Bounds, Cell, Rewards, Scenario};

/// The six actions as unit moves, in the paper's order (eq. 3): `+x -x +y -y +z -z`.
pub const ACTIONS: [[i32; 3]; 6] = [
    [1, 0, 0],
    [-1, 0, 0],
    [0, 1, 0],
    [0, -1, 0],
    [0, 0, 1],
    [0, 0, -1],
];

/// Number of actions.
pub const NUM_ACTIONS: usize = 6;

/// The opposite action: `+x <-> -x`, `+y <-> -y`, `+z <-> -z` (`action ^ 1`).
#[inline]
pub fn opposite(action: usize) -> usize {
    action ^ 1
}

/// The outcome of one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    /// The state after the step (the same state on a collision).
    pub next: usize,
    /// The reward of eqs. 5, 9, 10 (as selected by the [`Assist`]).
    pub reward: f64,
    /// The move collided (out of bounds or too close to an obstacle).
    pub collided: bool,
    /// The move reached the target (never together with `collided`).
    pub reached: bool,
}

/// What does not change when start or target move: shared between clones.
#[derive(Debug)]
struct Topology {
    bounds: Bounds,
    /// Cells along x, y, z.
    size: [usize; 3],
    /// Per state: the terminal would collide there.
    blocked: Vec<bool>,
    /// Per state and action: the next state (the same state on a collision).
    next: Vec<[u32; NUM_ACTIONS]>,
    /// Obstacle centres (scenario's, then the extra ones).
    obstacles: Vec<Cell>,
    terminal_safe_distance: f64,
}

/// The grid world of one scenario: precomputed transitions and distances.
#[derive(Debug, Clone)]
pub struct GridWorld {
    topo: Arc<Topology>,
    start: usize,
    target: usize,
    /// Per state: `d_t`, Euclidean distance to the target, cells.
    dist: Vec<f64>,
    /// `d_o = |target - start|`, cells.
    d_o: f64,
    rewards: Rewards,
}

fn fmt_cell(c: Cell) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

/// Euclidean distance between two cells, in cells (`d_o` and `d_t` of eq. 10).
pub fn cell_distance(a: Cell, b: Cell) -> f64 {
    let d2: i64 = (0..3)
        .map(|i| {
            let d = (a[i] - b[i]) as i64;
            d * d
        })
        .sum();
    (d2 as f64).sqrt()
}

/// Eq. 5 plus (if `assist.distance`) eq. 10, without eq. 9: `-collision_penalty` if the move
/// `collided`, else `+target_reward` if it reached the target (`at_target`: the new cell is
/// the target), else `-step_penalty`; then `+distance_reward * (d_o - d_t)` (cells).
///
/// The one place these equations are written: [`GridWorld::step`] and the relabelled rewards
/// of goal-conditioned learning ([`EnvModel::goal_rewards`](crate::env::EnvModel::goal_rewards))
/// both call it.
#[inline]
pub fn base_reward_of(
    r: &Rewards,
    collided: bool,
    at_target: bool,
    d_o: f64,
    d_t: f64,
    assist: Assist,
) -> f64 {
    let mut reward = if collided {
        -r.collision_penalty
    } else if at_target {
        r.target_reward
    } else {
        -r.step_penalty
    };
    if assist.distance {
        reward += r.distance_reward * (d_o - d_t);
    }
    reward
}

impl GridWorld {
    /// The world of a scenario (its bounds, obstacles, `terminal_safe_distance`, start,
    /// target and rewards).
    pub fn new(scenario: &Scenario) -> Result<GridWorld> {
        GridWorld::with_extra_obstacles(scenario, &[])
    }

    /// The world of a scenario with extra obstacle cells (the points Algorithm 2 adds when
    /// no arm pose can reach them). Errors if the start or the target becomes blocked.
    pub fn with_extra_obstacles(scenario: &Scenario, extra: &[Cell]) -> Result<GridWorld> {
        let bounds = scenario.bounds;
        for i in 0..3 {
            if bounds.min[i] > bounds.max[i] {
                return Err(Error::invalid(
                    "bounds",
                    format!("min {} max {}", fmt_cell(bounds.min), fmt_cell(bounds.max)),
                    "empty box",
                ));
            }
        }
        let size = bounds.size();
        let n = bounds.volume();
        if n > u32::MAX as usize {
            return Err(Error::invalid("bounds", n, "too many cells"));
        }
        let d_s = scenario.terminal_safe_distance;
        if !d_s.is_finite() || d_s < 0.0 {
            return Err(Error::invalid(
                "terminal_safe_distance",
                d_s,
                "must be a finite number >= 0",
            ));
        }
        let mut obstacles = scenario.obstacles.clone();
        obstacles.extend_from_slice(extra);

        let index = |c: Cell| -> Option<usize> {
            if !bounds.contains(c) {
                return None;
            }
            let ix = (c[0] - bounds.min[0]) as usize;
            let iy = (c[1] - bounds.min[1]) as usize;
            let iz = (c[2] - bounds.min[2]) as usize;
            Some((ix * size[1] + iy) * size[2] + iz)
        };

        // Blocked cells by the rule: distance to some obstacle centre <= d_s. Only cells
        // within floor(d_s) per axis of a centre can qualify. An extra obstacle (a point
        // no arm pose reaches) blocks its own cell only, whatever d_s.
        let mut blocked = vec![false; n];
        for &o in extra {
            if let Some(s) = index(o) {
                blocked[s] = true;
            }
        }
        let r = d_s.floor() as i32;
        for &o in &scenario.obstacles {
            for dx in -r..=r {
                for dy in -r..=r {
                    for dz in -r..=r {
                        let c = [o[0] + dx, o[1] + dy, o[2] + dz];
                        if let Some(s) = index(c) {
                            if cell_distance(c, o) <= d_s {
                                blocked[s] = true;
                            }
                        }
                    }
                }
            }
        }

        // Boxes in mm: cells whose centre is within d_s (mm) of the box by its rule.
        let d_s_mm = scenario.terminal_safe_distance_in_mm();
        let cell_mm = scenario.cell_mm;
        for ob in &scenario.obstacle_boxes_mm {
            let lo: [i32; 3] = std::array::from_fn(|i| {
                (((ob.min_mm[i] - d_s_mm) / cell_mm).floor() as i32).max(bounds.min[i])
            });
            let hi: [i32; 3] = std::array::from_fn(|i| {
                (((ob.max_mm[i] + d_s_mm) / cell_mm).ceil() as i32).min(bounds.max[i])
            });
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        let c = [x, y, z];
                        let p = c.map(|v| v as f64 * cell_mm);
                        if let Some(s) = index(c) {
                            if !blocked[s] && ob.terminal_distance_mm(p) <= d_s_mm {
                                blocked[s] = true;
                            }
                        }
                    }
                }
            }
        }

        let mut next = vec![[0u32; NUM_ACTIONS]; n];
        for ix in 0..size[0] {
            for iy in 0..size[1] {
                for iz in 0..size[2] {
                    let s = (ix * size[1] + iy) * size[2] + iz;
                    let c = [
                        bounds.min[0] + ix as i32,
                        bounds.min[1] + iy as i32,
                        bounds.min[2] + iz as i32,
                    ];
                    for (a, m) in ACTIONS.iter().enumerate() {
                        let nc = [c[0] + m[0], c[1] + m[1], c[2] + m[2]];
                        next[s][a] = match index(nc) {
                            Some(ns) if !blocked[ns] => ns as u32,
                            _ => s as u32,
                        };
                    }
                }
            }
        }

        let topo = Arc::new(Topology {
            bounds,
            size,
            blocked,
            next,
            obstacles,
            terminal_safe_distance: d_s,
        });
        let mut world = GridWorld {
            topo,
            start: 0,
            target: 0,
            dist: vec![0.0; n],
            d_o: 0.0,
            rewards: scenario.rewards,
        };
        let start = world.free_state("start", scenario.start)?;
        let target = world.free_state("target", scenario.target)?;
        if start == target {
            return Err(Error::argument(
                "target",
                fmt_cell(scenario.target),
                "equals the start cell",
            ));
        }
        world.start = start;
        world.target = target;
        world.refresh_distances();
        Ok(world)
    }

    /// The state of a cell that must be inside bounds and not blocked.
    fn free_state(&self, what: &str, cell: Cell) -> Result<usize> {
        let s = self
            .state_of(cell)
            .ok_or_else(|| Error::argument(what, fmt_cell(cell), "lies outside bounds"))?;
        if self.topo.blocked[s] {
            return Err(Error::argument(
                what,
                fmt_cell(cell),
                format!(
                    "is blocked: within terminal_safe_distance {} of an obstacle centre",
                    self.topo.terminal_safe_distance
                ),
            ));
        }
        Ok(s)
    }

    fn refresh_distances(&mut self) {
        let t = self.cell_of(self.target);
        let n = self.num_states();
        for s in 0..n {
            self.dist[s] = cell_distance(self.cell_of(s), t);
        }
        self.d_o = self.dist[self.start];
    }

    /// Number of states (cells inside bounds, blocked ones included).
    #[inline]
    pub fn num_states(&self) -> usize {
        self.topo.blocked.len()
    }

    /// The bounds of the world.
    pub fn bounds(&self) -> Bounds {
        self.topo.bounds
    }

    /// All obstacle centres: the scenario's, then the extra ones.
    pub fn obstacles(&self) -> &[Cell] {
        &self.topo.obstacles
    }

    /// The terminal's safe distance `d_s`, cells.
    pub fn terminal_safe_distance(&self) -> f64 {
        self.topo.terminal_safe_distance
    }

    /// The state of a cell; `None` outside bounds.
    #[inline]
    pub fn state_of(&self, cell: Cell) -> Option<usize> {
        let b = &self.topo.bounds;
        if !b.contains(cell) {
            return None;
        }
        let size = self.topo.size;
        let ix = (cell[0] - b.min[0]) as usize;
        let iy = (cell[1] - b.min[1]) as usize;
        let iz = (cell[2] - b.min[2]) as usize;
        Some((ix * size[1] + iy) * size[2] + iz)
    }

    /// The cell of a state. Panics if `state >= num_states()`.
    #[inline]
    pub fn cell_of(&self, state: usize) -> Cell {
        assert!(state < self.num_states(), "state {state} out of range");
        let size = self.topo.size;
        let b = &self.topo.bounds;
        let iz = state % size[2];
        let iy = (state / size[2]) % size[1];
        let ix = state / (size[1] * size[2]);
        [
            b.min[0] + ix as i32,
            b.min[1] + iy as i32,
            b.min[2] + iz as i32,
        ]
    }

    /// The start state.
    #[inline]
    pub fn start(&self) -> usize {
        self.start
    }

    /// The target state.
    #[inline]
    pub fn target(&self) -> usize {
        self.target
    }

    /// Move the target (goal-conditioned use). Errors if the cell is out of bounds,
    /// blocked, or the start cell. Updates `d_t` and `d_o`.
    pub fn set_target(&mut self, cell: Cell) -> Result<()> {
        let s = self.free_state("target", cell)?;
        if s == self.start {
            return Err(Error::argument(
                "target",
                fmt_cell(cell),
                "equals the start cell",
            ));
        }
        self.target = s;
        self.refresh_distances();
        Ok(())
    }

    /// Move the start. Errors if the cell is out of bounds, blocked, or the target cell.
    /// Updates `d_o`.
    pub fn set_start(&mut self, cell: Cell) -> Result<()> {
        let s = self.free_state("start", cell)?;
        if s == self.target {
            return Err(Error::argument(
                "start",
                fmt_cell(cell),
                "equals the target cell",
            ));
        }
        self.start = s;
        self.d_o = self.dist[s];
        Ok(())
    }

    /// Whether the terminal would collide in this cell (an obstacle centre within `d_s`).
    #[inline]
    pub fn is_blocked(&self, state: usize) -> bool {
        self.topo.blocked[state]
    }

    /// Whether moving from `state` with `action` collides (out of bounds or blocked cell).
    #[inline]
    pub fn move_collides(&self, state: usize, action: usize) -> bool {
        self.topo.next[state][action] as usize == state
    }

    /// The next state of (state, action) without the reward (the same state on a collision).
    #[inline]
    pub fn next_state(&self, state: usize, action: usize) -> usize {
        self.topo.next[state][action] as usize
    }

    /// The transition table, one row of six next states per state.
    #[inline]
    pub fn transitions(&self) -> &[[u32; NUM_ACTIONS]] {
        &self.topo.next
    }

    /// `d_o = |target - start|`, cells.
    #[inline]
    pub fn start_distance_cells(&self) -> f64 {
        self.d_o
    }

    /// `d_t`: distance from the state's cell to the target, cells.
    #[inline]
    pub fn distance_to_target_cells(&self, state: usize) -> f64 {
        self.dist[state]
    }

    /// The reward parameters.
    pub fn rewards(&self) -> &Rewards {
        &self.rewards
    }

    /// Eq. 5 plus (if `assist.distance`) eq. 10 for (state, action), without eq. 9.
    #[inline]
    pub fn base_reward(&self, state: usize, action: usize, assist: Assist) -> f64 {
        let next = self.topo.next[state][action] as usize;
        let collided = next == state;
        base_reward_of(
            &self.rewards,
            collided,
            next == self.target,
            self.d_o,
            self.dist[next],
            assist,
        )
    }

    /// Eq. 9's extra term (<= 0): given the action of the previous step if it collided.
    #[inline]
    pub fn detour_penalty(
        &self,
        action: usize,
        collided: bool,
        last_collided_action: Option<usize>,
    ) -> f64 {
        match last_collided_action {
            Some(_) if collided => -self.rewards.repeat_collision_penalty,
            Some(prev) if opposite(action) == prev => -self.rewards.reverse_after_collision_penalty,
            _ => 0.0,
        }
    }

    /// One move of the terminal from `state` with `action`. `last_collided_action` is the
    /// action of the previous step of the episode if that step collided (eq. 9), else
    /// `None`. Panics if `action >= 6` or `state` is out of range.
    #[inline]
    pub fn step(
        &self,
        state: usize,
        action: usize,
        last_collided_action: Option<usize>,
        assist: Assist,
    ) -> Transition {
        let next = self.topo.next[state][action] as usize;
        let collided = next == state;
        let reached = !collided && next == self.target;
        let mut reward = self.base_reward(state, action, assist);
        if assist.detour {
            reward += self.detour_penalty(action, collided, last_collided_action);
        }
        Transition {
            next,
            reward,
            collided,
            reached,
        }
    }

    /// Breadth-first shortest path over free cells from start to target, both included;
    /// neighbours are expanded in action order, so the result is deterministic. `None` if
    /// the target cannot be reached.
    pub fn shortest_path(&self) -> Option<Vec<Cell>> {
        let n = self.num_states();
        const NONE: u32 = u32::MAX;
        let mut parent = vec![NONE; n];
        let mut queue = VecDeque::new();
        parent[self.start] = self.start as u32;
        queue.push_back(self.start);
        while let Some(s) = queue.pop_front() {
            if s == self.target {
                let mut path = vec![self.cell_of(s)];
                let mut cur = s;
                while cur != self.start {
                    cur = parent[cur] as usize;
                    path.push(self.cell_of(cur));
                }
                path.reverse();
                return Some(path);
            }
            for &ns in &self.topo.next[s] {
                let ns = ns as usize;
                if parent[ns] == NONE {
                    parent[ns] = s as u32;
                    queue.push_back(ns);
                }
            }
        }
        None
    }

    /// All cells the terminal may occupy (not blocked), in state order.
    pub fn free_cells(&self) -> Vec<Cell> {
        (0..self.num_states())
            .filter(|&s| !self.topo.blocked[s])
            .map(|s| self.cell_of(s))
            .collect()
    }

    /// A 64-bit FNV-1a fingerprint of what a Q-table depends on: bounds, blocked cells and
    /// target (not the start, not the rewards).
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv::new();
        let b = self.topo.bounds;
        for v in b.min.iter().chain(b.max.iter()) {
            h.write(&v.to_le_bytes());
        }
        for (s, &bl) in self.topo.blocked.iter().enumerate() {
            if bl {
                h.write(&(s as u64).to_le_bytes());
            }
        }
        h.write(b"target");
        h.write(&(self.target as u64).to_le_bytes());
        h.finish()
    }

    /// Number of blocked cells inside bounds.
    pub fn num_blocked(&self) -> usize {
        self.topo.blocked.iter().filter(|&&b| b).count()
    }
}

/// 64-bit FNV-1a, for fingerprints and checksums (stable across platforms and versions).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Fnv(u64);

impl Fnv {
    pub(crate) fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    pub(crate) fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    pub(crate) fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn simple() -> GridWorld {
        GridWorld::new(&Scenario::builtin("paper_simple").unwrap()).unwrap()
    }

    #[test]
    fn opposite_pairs() {
        for (a, m) in ACTIONS.iter().enumerate() {
            let o = opposite(a);
            assert_ne!(a, o);
            assert_eq!(opposite(o), a);
            assert_eq!(m.map(|v| -v), ACTIONS[o]);
        }
    }

    #[test]
    fn state_cell_roundtrip() {
        let w = simple();
        assert_eq!(w.num_states(), 7 * 9 * 8);
        for s in 0..w.num_states() {
            assert_eq!(w.state_of(w.cell_of(s)), Some(s));
        }
        assert_eq!(w.state_of([4, 0, 0]), None);
        assert_eq!(w.cell_of(w.start()), [0, -2, 4]);
        assert_eq!(w.cell_of(w.target()), [0, 3, 0]);
    }

    #[test]
    fn blocked_cells_are_the_obstacles_when_ds_below_one() {
        let sc = Scenario::builtin("paper_simple").unwrap();
        let w = GridWorld::new(&sc).unwrap();
        assert_eq!(w.num_blocked(), sc.obstacles.len());
        for o in &sc.obstacles {
            assert!(w.is_blocked(w.state_of(*o).unwrap()));
        }
        assert_eq!(w.free_cells().len(), w.num_states() - sc.obstacles.len());
    }

    #[test]
    fn extra_obstacles_and_set_target_errors() {
        let sc = Scenario::builtin("paper_simple").unwrap();
        assert!(GridWorld::with_extra_obstacles(&sc, &[[0, 3, 0]]).is_err());
        assert!(GridWorld::with_extra_obstacles(&sc, &[[0, -2, 4]]).is_err());
        let w = GridWorld::with_extra_obstacles(&sc, &[[0, 0, 0]]).unwrap();
        assert!(w.is_blocked(w.state_of([0, 0, 0]).unwrap()));
        let mut w = simple();
        assert!(w.set_target([0, 1, 0]).is_err());
        assert!(w.set_target([9, 9, 9]).is_err());
        assert!(w.set_target([0, -2, 4]).is_err());
        w.set_target([2, 2, 2]).unwrap();
        assert_eq!(w.cell_of(w.target()), [2, 2, 2]);
        assert_eq!(w.distance_to_target_cells(w.target()), 0.0);
        w.set_start([2, 2, 0]).unwrap();
        assert_eq!(w.start_distance_cells(), 2.0);
    }
}
