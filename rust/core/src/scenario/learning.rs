//! A scenario's learning sections: [`Rewards`] (eqs. 5, 9, 10; reward units), [`Learning`]
//! (the learner's options, declared once with `option_set!`: docs/SCENARIOS.md "Options of a
//! run: one declaration"), [`Assist`] (the assisted strategies) and the named choices
//! [`InitialQ`] and [`QPrecision`].

use serde::{Deserialize, Serialize};

use super::Scenario;
use crate::error::{Error, Result};
use crate::options::{check_all, named_enum, option_set, Domain, FromOption, OptionValue};

/// Reward parameters (eqs. 5, 9, 10). Penalties are given as positive magnitudes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rewards {
    /// r (eq. 5): reward for reaching the target.
    pub target_reward: f64,
    /// p (eq. 5): penalty of a step that neither collides nor reaches the target.
    pub step_penalty: f64,
    /// P (eq. 5): penalty of a collision (obstacle or bounds).
    pub collision_penalty: f64,
    /// p_e (eq. 9): extra penalty when the step after a collision collides again.
    pub repeat_collision_penalty: f64,
    /// p_o (eq. 9): extra penalty when the step after a collision takes the opposite action.
    pub reverse_after_collision_penalty: f64,
    /// r_e (eq. 10): reward per cell of progress, `r_e * (d_o - d_t)`.
    pub distance_reward: f64,
}

impl Default for Rewards {
    fn default() -> Self {
        Rewards {
            target_reward: 20000.0,
            step_penalty: 15000.0,
            collision_penalty: 8000.0,
            repeat_collision_penalty: 230000.0,
            reverse_after_collision_penalty: 10000.0,
            distance_reward: 40.0,
        }
    }
}

/// Default episode cap of `episodes = "auto"` (`--episodes auto`), episodes.
pub const AUTO_EPISODE_CAP: u32 = 1_000_000;

option_set! {
    /// Q-learning parameters (eqs. 6-7) and the assisted strategies: the scenario's
    /// `learning` section and the options of a training run (the one declaration of the
    /// learning options: the scenario schema, the request layer, the CLI's flags, the Python
    /// keywords, the stub and the docs' table are derived from it; see [`crate::options`]).
    pub struct Learning ("learning") {
        /// eta_set: learning episodes; with `episodes = "auto"` (ours), train until the
        /// greedy path reaches the target and stops changing, under `episode_cap`.
        episodes: u32 = 10_000; "episodes", Domain::IntOrAuto { min: 1, max: u32::MAX as i128 }, "episodes",
            set = set_episodes;
        /// Whether `episodes` is a cap and the run stops when the greedy path settles (set
        /// by `episodes = "auto"`; see docs/SCENARIOS.md).
        episodes_auto: bool = false; "", Domain::Bool, "";
        /// Seed of the learner's random generator.
        seed: u64 = 0; "seed", Domain::u64_from(0), "";
        /// Detour encouraging (eq. 9) on or off.
        assist_detour: bool = true; "detour", Domain::Bool, "";
        /// Distance assistance (eq. 10) on or off.
        assist_distance: bool = true; "distance", Domain::Bool, "";
        /// Step cap of an episode and of the greedy rollout (the paper gives none).
        max_steps_per_episode: u32 = 1000; "max_steps_per_episode", Domain::u32_from(1), "steps";
        /// How the Q-table starts: `zero` (the paper, eq. 6) or `distance` (ours: an
        /// optimistic bound from the Manhattan distance to the target; see docs/SCENARIOS.md).
        initial_q: InitialQ = InitialQ::Zero; "initial_q", InitialQ::DOMAIN, "";
        /// The type of the Q-values: `f64` (the paper's arithmetic) or `f32` (ours: half the
        /// memory per state; updates computed in f64, stored rounded).
        q_precision: QPrecision = QPrecision::F64; "q_precision", QPrecision::DOMAIN, "";
        /// alpha: learning rate of eq. 6.
        alpha: f64 = 0.05; "alpha", Domain::UNIT_OPEN, "";
        /// gamma: discount factor of eq. 6.
        gamma: f64 = 0.9; "gamma", Domain::UNIT, "";
        /// epsilon at episode 0 (eq. 7: 0.1).
        epsilon_start: f64 = 0.1; "epsilon_start", Domain::UNIT, "";
        /// M: episodes over which epsilon falls linearly to 0 (eq. 7).
        epsilon_decay_episodes: u32 = 9900; "epsilon_decay_episodes", Domain::u32_from(0), "episodes";
        /// Env-step budget (ours; 0: none, the paper's): training stops after this many env
        /// steps over all episodes, mid-episode if need be, or after `episodes`, whichever
        /// comes first.
        max_env_steps: u64 = 0; "max_env_steps", Domain::u64_from(0), "env steps";
        /// What epsilon falls over: `episodes` (the paper's eq. 7, over
        /// `epsilon_decay_episodes`) or `env_steps` (ours: over the first
        /// `epsilon_decay_fraction` x `max_env_steps` env steps; needs `max_env_steps`).
        epsilon_schedule: EpsilonSchedule = EpsilonSchedule::Episodes; "epsilon_schedule", EpsilonSchedule::DOMAIN, "";
        /// With `epsilon_schedule = "env_steps"`: the fraction of `max_env_steps` over which
        /// epsilon falls linearly to 0 (0.99: the paper's M / eta_set = 9900 / 10000).
        epsilon_decay_fraction: f64 = 0.99; "epsilon_decay_fraction", Domain::NON_NEGATIVE, "";
    }
}

/// `episodes`: a number of episodes, or `"auto"` (then `episodes` is the cap
/// [`AUTO_EPISODE_CAP`] until `episode_cap` says otherwise).
fn set_episodes(o: &mut Learning, key: &str, v: &OptionValue) -> Result<()> {
    const DOMAIN: Domain = Domain::IntOrAuto {
        min: 1,
        max: u32::MAX as i128,
    };
    // As a request key, a number is a fixed run; as the scenario field (`learning.episodes`,
    // a number only), it stays with the file's `episodes_auto`.
    let request = key == "episodes";
    if request && matches!(v, OptionValue::Text(t) if t == "auto") {
        o.episodes_auto = true;
        o.episodes = AUTO_EPISODE_CAP;
        return Ok(());
    }
    let domain = if request { DOMAIN } else { Domain::u32_from(1) };
    o.episodes = u32::from_option(key, &domain, v)?;
    if request {
        o.episodes_auto = false;
    }
    Ok(())
}

impl Learning {
    /// The scenario's `learning` section.
    pub fn from_scenario(s: &Scenario) -> Self {
        s.learning
    }

    /// The assisted strategies on or off (eqs. 9 and 10).
    pub fn assist(&self) -> Assist {
        Assist {
            detour: self.assist_detour,
            distance: self.assist_distance,
        }
    }

    /// Both strategies as one [`Assist`].
    pub fn set_assist(&mut self, a: Assist) {
        self.assist_detour = a.detour;
        self.assist_distance = a.distance;
    }

    /// `episodes = "auto"`: train until the greedy path settles, under [`AUTO_EPISODE_CAP`].
    pub fn auto(mut self) -> Self {
        self.episodes_auto = true;
        self.episodes = AUTO_EPISODE_CAP;
        self
    }

    /// Check the ranges and the rules between options; the error names the option.
    pub fn validate(&self) -> Result<()> {
        check_all(Self::OPTIONS, self, |i| {
            if i.key.is_empty() {
                i.field
            } else {
                i.key
            }
        })?;
        if self.epsilon_schedule == EpsilonSchedule::EnvSteps {
            let schedule = self.epsilon_schedule.name();
            if self.max_env_steps == 0 {
                return Err(Error::argument(
                    "epsilon_schedule",
                    schedule,
                    "needs a budget: max_env_steps >= 1",
                ));
            }
            if self.episodes_auto {
                return Err(Error::argument(
                    "epsilon_schedule",
                    schedule,
                    "does not combine with episodes = \"auto\" (which has its own schedule)",
                ));
            }
        }
        Ok(())
    }

    /// D of `epsilon_schedule = "env_steps"`: `epsilon_decay_fraction * max_env_steps`, the
    /// env steps over which epsilon falls to 0.
    pub fn epsilon_decay_steps(&self) -> f64 {
        self.epsilon_decay_fraction * self.max_env_steps as f64
    }

    /// Exploration rate of env step `t` (counted from 0 over the run) with
    /// `epsilon_schedule = "env_steps"`: `epsilon_start * (1 - t / D)` for `t < D`, else 0
    /// ([`Learning::epsilon_decay_steps`]).
    pub fn epsilon_at_step(&self, t: u64) -> f64 {
        let d = self.epsilon_decay_steps();
        let t = t as f64;
        if t < d {
            self.epsilon_start * (1.0 - t / d)
        } else {
            0.0
        }
    }

    /// Exploration rate of episode `episode` (counted from 0), eq. 7.
    pub fn epsilon(&self, episode: u32) -> f64 {
        let m = self.epsilon_decay_episodes;
        if m == 0 || episode > m {
            0.0
        } else {
            self.epsilon_start * (1.0 - episode as f64 / m as f64)
        }
    }
}

/// Which assisted-learning strategies shape the reward.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Assist {
    /// Detour encouraging, eq. 9.
    pub detour: bool,
    /// Distance assistance, eq. 10.
    pub distance: bool,
}

impl Assist {
    /// Both strategies on ("with assisted learning").
    pub fn on() -> Self {
        Assist {
            detour: true,
            distance: true,
        }
    }

    /// Both off: eq. 5 alone ("without assisted learning").
    pub fn off() -> Self {
        Assist {
            detour: false,
            distance: false,
        }
    }

    /// The scenario's `learning.assist_detour` / `learning.assist_distance`.
    pub fn from_scenario(s: &Scenario) -> Self {
        s.learning.assist()
    }
}

named_enum! {
    /// What the learner's epsilon falls over (`learning.epsilon_schedule`).
    pub enum EpsilonSchedule (default Episodes) {
        /// Over episodes, eq. 7 (`epsilon_decay_episodes`): the paper's, the default.
        Episodes = "episodes",
        /// Ours: over env steps, linearly to 0 over the first `epsilon_decay_fraction` x
        /// `max_env_steps` steps of the run (a budget in env steps).
        EnvSteps = "env_steps",
    }
}

named_enum! {
    /// How the learner's Q-table starts (`learning.initial_q`).
    pub enum InitialQ (default Zero) {
        /// Q = 0 everywhere: the paper's learner, the default of every scenario.
        Zero = "zero",
        /// Ours: Q(s, a) starts at an optimistic bound of the return of reaching the target
        /// from the move's next cell in its Manhattan distance of moves (the rule of
        /// `crate::qlearning`).
        Distance = "distance",
    }
}

named_enum! {
    /// The type the learner stores its Q-values in (`learning.q_precision`).
    pub enum QPrecision (default F64) {
        /// 64-bit floats (48 bytes of Q-values per state): the default of every scenario.
        F64 = "f64",
        /// Ours: 32-bit floats (24 bytes per state). Every update is computed in f64 as with
        /// `F64` and its result rounded to the nearest f32 when stored.
        F32 = "f32",
    }
}

impl QPrecision {
    /// Bytes of one Q-value (8 or 4).
    pub fn value_bytes(self) -> usize {
        match self {
            QPrecision::F64 => 8,
            QPrecision::F32 => 4,
        }
    }
}
