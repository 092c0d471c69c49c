//! One env's running episode ([`Episode`]): reset, step, the vector observation.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{EnvModel, OBS_COLLIDED, OBS_FLAGS, OBS_TARGET, OBS_TERMINAL};
use crate::grid::GridWorld;

/// One step's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepOutcome {
    /// Reward, times `reward_scale`.
    pub reward: f64,
    /// The move collided (the terminal stayed).
    pub collided: bool,
    /// The terminal reached the target: the episode terminates.
    pub reached: bool,
    /// Eq. 9's part of the reward (<= 0, before `reward_scale`; 0 without detour assist).
    pub detour_penalty: f64,
}

/// One environment's running episode.
#[derive(Debug, Clone)]
pub struct Episode {
    pub(super) state: u32,
    target: u32,
    last_collided_action: Option<u8>,
    pub(super) collided: bool,
    pub(super) steps: u32,
    rng: ChaCha8Rng,
    /// The world with this episode's target, when it differs from the model's.
    own_world: Option<GridWorld>,
}

impl Episode {
    /// A new episode at the model's start (call [`Episode::reset`] before stepping).
    pub fn new(model: &EnvModel) -> Episode {
        Episode {
            state: model.world.start() as u32,
            target: model.world.target() as u32,
            last_collided_action: None,
            collided: false,
            steps: 0,
            rng: ChaCha8Rng::seed_from_u64(0),
            own_world: None,
        }
    }

    /// Seed the generator of random targets.
    pub fn seed(&mut self, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }

    #[inline]
    fn world<'a>(&'a self, model: &'a EnvModel) -> &'a GridWorld {
        self.own_world.as_ref().unwrap_or(&model.world)
    }

    /// Start a new episode at the start cell (drawing a target if `random_target`).
    pub fn reset(&mut self, model: &EnvModel) {
        let base = &model.world;
        self.state = base.start() as u32;
        self.last_collided_action = None;
        self.collided = false;
        self.steps = 0;
        if model.opts.random_target {
            let k = self.rng.random_range(0..model.target_states.len());
            let t = model.target_states[k];
            self.target = t;
            if t as usize == base.target() {
                self.own_world = None;
            } else {
                let w = self.own_world.get_or_insert_with(|| base.clone());
                w.set_target(base.cell_of(t as usize))
                    .expect("target candidates are free cells other than the start");
            }
        } else {
            self.target = base.target() as u32;
            self.own_world = None;
        }
    }

    /// Move the terminal with `action` (< 6; checked by the caller).
    #[inline]
    pub fn step(&mut self, model: &EnvModel, action: usize) -> StepOutcome {
        let assist = model.opts.assist;
        let last = self.last_collided_action.map(usize::from);
        let world = self.world(model);
        let t = world.step(self.state as usize, action, last, assist);
        let detour_penalty = if assist.detour {
            world.detour_penalty(action, t.collided, last)
        } else {
            0.0
        };
        self.state = t.next as u32;
        self.collided = t.collided;
        self.last_collided_action = if t.collided { Some(action as u8) } else { None };
        self.steps += 1;
        StepOutcome {
            reward: t.reward * model.opts.reward_scale,
            collided: t.collided,
            reached: t.reached,
            detour_penalty,
        }
    }

    /// The terminal's state.
    #[inline]
    pub fn state(&self) -> usize {
        self.state as usize
    }

    /// The target's state.
    #[inline]
    pub fn target(&self) -> usize {
        self.target as usize
    }

    /// Steps taken since the reset.
    #[inline]
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Whether the last step collided.
    #[inline]
    pub fn last_collided(&self) -> bool {
        self.collided
    }

    /// The action of the last step if it collided (eq. 9's memory).
    #[inline]
    pub fn last_collided_action(&self) -> Option<usize> {
        self.last_collided_action.map(usize::from)
    }

    /// Distance from the terminal to the target, cells.
    #[inline]
    pub fn distance_to_target(&self, model: &EnvModel) -> f64 {
        self.world(model)
            .distance_to_target_cells(self.state as usize)
    }

    /// `d_o`: distance from the start to this episode's target, cells.
    pub fn start_distance(&self, model: &EnvModel) -> f64 {
        self.world(model).start_distance_cells()
    }

    /// Write the vector observation into `out` (length [`VECTOR_OBS_DIM`](super::VECTOR_OBS_DIM)).
    #[inline]
    pub fn write_vector_obs(&self, model: &EnvModel, out: &mut [f32]) {
        let row = &model.rows[self.state as usize];
        let trow = &model.rows[self.target as usize];
        out[OBS_TERMINAL].copy_from_slice(&row[..3]);
        out[OBS_TARGET].copy_from_slice(&trow[..3]);
        out[OBS_FLAGS].copy_from_slice(&row[3..9]);
        out[OBS_COLLIDED] = if self.collided { 1.0 } else { 0.0 };
    }
}
