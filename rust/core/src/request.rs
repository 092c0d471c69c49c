//! Requests: what a caller asks of a training or planning run, as optional overrides of the
//! scenario's settings, resolved in one place.
//!
//! Entry points:
//! - [`TrainRequest`] — episodes, seed, assistance (eqs. 9 and 10, together or each on its
//!   own), the step cap, the initial Q-table rule and the Q-values' precision; [`TrainRequest::resolve`] against a scenario gives the
//!   [`TrainOptions`] of [`crate::qlearning::train`].
//! - [`PlanRequest`] — a training request plus the re-plan cap and the path learner;
//!   [`PlanRequest::resolve`] gives the [`PlanOptions`] and [`LearnerKind`] of
//!   [`crate::replanning::plan`].
//! - [`parse_int`] — the integer text of a command-line flag, checked with the same words as
//!   [`TrainRequest::resolve`] uses.
//!
//! The `sixaxis` CLI maps its flags to a request and the Python bindings map their keywords
//! to one; nothing else fills defaults or checks ranges, so both front ends take the same
//! values, use the same defaults and give the same error text (named after the Python
//! keyword: `seed`, `episodes`, ...). A field left `None` takes the scenario's value.
//! Integers are carried as `i128` so that an out-of-range value (a negative seed, an episode
//! count past `u32`) reaches [`TrainRequest::resolve`] and gets its error there.
//!
//! ```
//! use sixaxis_core::request::{PlanRequest, TrainRequest};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let req = TrainRequest { seed: Some(3), detour: Some(false), ..Default::default() };
//! let opts = req.resolve(&s).unwrap();
//! assert_eq!((opts.seed, opts.episodes), (3, 10_000));
//! assert!(!opts.assist.detour && opts.assist.distance);
//! let bad = TrainRequest { seed: Some(-1), ..Default::default() };
//! assert_eq!(
//!     bad.resolve(&s).unwrap_err().to_string(),
//!     "invalid argument `seed` = -1: must be an integer >= 0"
//! );
//! assert!(PlanRequest::default().resolve(&s).is_ok());
//! ```

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::qlearning::TrainOptions;
use crate::replanning::PlanOptions;
use crate::scenario::{InitialQ, QPrecision, Scenario};

/// Overrides of a training run; `None` takes the scenario's `learning` value.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainRequest {
    /// eta_set: learning episodes, `1..=u32::MAX`.
    pub episodes: Option<i128>,
    /// `episodes = "auto"`: train until the greedy path reaches the target and stops
    /// changing (the rule of [`crate::qlearning`]), under `episode_cap`.
    pub episodes_auto: Option<bool>,
    /// Episode cap of `episodes_auto`, `1..=u32::MAX` (default
    /// [`crate::qlearning::AUTO_EPISODE_CAP`]); only with `episodes_auto`.
    pub episode_cap: Option<i128>,
    /// Seed of the learner's generator, `0..=u64::MAX`.
    pub seed: Option<i128>,
    /// Both assisted strategies (eqs. 9 and 10) on or off; `detour` / `distance` then
    /// switch one of them.
    pub assist: Option<bool>,
    /// Detour encouraging (eq. 9) on or off (after `assist`).
    pub detour: Option<bool>,
    /// Distance assistance (eq. 10) on or off (after `assist`).
    pub distance: Option<bool>,
    /// Step cap of an episode and of the greedy rollout, `1..=u32::MAX`.
    pub max_steps_per_episode: Option<i128>,
    /// How the Q-table starts, by name: `"zero"` (the paper) or `"distance"` (see
    /// [`crate::qlearning::distance_bound_table`]); default the scenario's
    /// `learning.initial_q`.
    pub initial_q: Option<String>,
    /// The type of the Q-values, by name: `"f64"` (the default) or `"f32"` (half the
    /// memory per state); default the scenario's `learning.q_precision`.
    pub q_precision: Option<String>,
}

/// The path learners [`PlanRequest::learner`] can name.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LearnerKind {
    /// Tabular Q-learning, the paper's ([`crate::replanning::QLearner`]).
    #[default]
    Qlearning,
    /// The breadth-first shortest path ([`crate::replanning::BfsLearner`]).
    Bfs,
}

impl LearnerKind {
    /// Every name, in the order of the docs.
    pub const NAMES: &'static [&'static str] = &["qlearning", "bfs"];

    /// The learner of a name (`qlearning`, `bfs`); the error lists the names.
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "qlearning" => Ok(LearnerKind::Qlearning),
            "bfs" => Ok(LearnerKind::Bfs),
            _ => Err(Error::argument(
                "learner",
                name,
                format!(
                    "must be one of {} (or, from Python, a callable)",
                    Self::NAMES.join(", ")
                ),
            )),
        }
    }
}

/// Overrides of an Algorithm 2 run: the training request of every round, the re-plan cap
/// and the path learner. (Room to grow: a planning mode and its n_d rule go here.)
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlanRequest {
    /// Learning options of every round.
    pub train: TrainRequest,
    /// Re-plans allowed before giving up, `0..=u32::MAX` (default: the scenario's
    /// `planning.max_replans`).
    pub max_replans: Option<i128>,
    /// The path learner by name (default `qlearning`; see [`LearnerKind::from_name`]).
    pub learner: Option<String>,
}

/// The words of an integer's domain, as every error about one says them.
pub fn int_domain(min: i128, max: i128) -> String {
    if max == u64::MAX as i128 {
        format!("must be an integer >= {min}")
    } else {
        format!("must be an integer in {min}..={max}")
    }
}

/// `value` checked against `domain` = (name, min, max), e.g. [`SEED`]; the error names it.
pub fn in_domain(domain: (&str, i128, i128), value: i128) -> Result<i128> {
    let (name, min, max) = domain;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(Error::argument(name, value, int_domain(min, max)))
    }
}

/// Domains of the integer fields: (name, min, max).
pub const SEED: (&str, i128, i128) = ("seed", 0, u64::MAX as i128);
/// See [`SEED`].
pub const EPISODES: (&str, i128, i128) = ("episodes", 1, u32::MAX as i128);
/// See [`SEED`].
pub const EPISODE_CAP: (&str, i128, i128) = ("episode_cap", 1, u32::MAX as i128);
/// See [`SEED`].
pub const MAX_STEPS: (&str, i128, i128) = ("max_steps_per_episode", 1, u32::MAX as i128);
/// See [`SEED`].
pub const MAX_REPLANS: (&str, i128, i128) = ("max_replans", 0, u32::MAX as i128);

/// `--episodes` text: a whole number of episodes, or `auto` (then `(None, true)`).
pub fn parse_episodes(text: &str) -> Result<(Option<i128>, bool)> {
    if text.trim() == "auto" {
        return Ok((None, true));
    }
    parse_int(EPISODES, text).map(|n| (Some(n), false))
}

/// The integer written in `text` (a command-line value), or the error
/// [`TrainRequest::resolve`] would give for a value out of `domain` (e.g. [`SEED`]).
pub fn parse_int(domain: (&str, i128, i128), text: &str) -> Result<i128> {
    let (name, min, max) = domain;
    text.trim()
        .parse::<i128>()
        .map_err(|_| Error::argument(name, text, int_domain(min, max)))
}

fn checked(domain: (&str, i128, i128), v: Option<i128>) -> Result<Option<i128>> {
    v.map(|v| in_domain(domain, v)).transpose()
}

impl TrainRequest {
    /// The scenario's learning options with these overrides, every range checked.
    pub fn resolve(&self, s: &Scenario) -> Result<TrainOptions> {
        let mut opts = TrainOptions::from_scenario(s);
        if let Some(v) = checked(EPISODES, self.episodes)? {
            opts.episodes = v as u32;
        }
        let cap = checked(EPISODE_CAP, self.episode_cap)?;
        if self.episodes_auto == Some(true) {
            if let Some(n) = self.episodes {
                return Err(Error::argument(
                    "episodes",
                    n,
                    "is either a number of episodes or \"auto\", not both",
                ));
            }
            opts = opts.auto();
            if let Some(c) = cap {
                opts.episodes = c as u32;
            }
        } else if let Some(c) = cap {
            return Err(Error::argument(
                "episode_cap",
                c,
                "applies only with episodes = \"auto\"",
            ));
        }
        if let Some(v) = checked(SEED, self.seed)? {
            opts.seed = v as u64;
        }
        if let Some(v) = checked(MAX_STEPS, self.max_steps_per_episode)? {
            opts.max_steps_per_episode = v as u32;
        }
        if let Some(a) = self.assist {
            opts.assist.detour = a;
            opts.assist.distance = a;
        }
        if let Some(d) = self.detour {
            opts.assist.detour = d;
        }
        if let Some(d) = self.distance {
            opts.assist.distance = d;
        }
        if let Some(name) = &self.initial_q {
            opts.initial_q = InitialQ::from_name("initial_q", name)?;
        }
        if let Some(name) = &self.q_precision {
            opts.q_precision = QPrecision::from_name("q_precision", name)?;
        }
        opts.validate()?;
        Ok(opts)
    }
}

impl PlanRequest {
    /// The scenario's planning options with these overrides, and the learner asked for.
    pub fn resolve(&self, s: &Scenario) -> Result<(PlanOptions, LearnerKind)> {
        let mut opts = PlanOptions::from_scenario(s);
        opts.train = self.train.resolve(s)?;
        if let Some(v) = checked(MAX_REPLANS, self.max_replans)? {
            opts.max_replans = v as u32;
        }
        let learner = match &self.learner {
            Some(name) => LearnerKind::from_name(name)?,
            None => LearnerKind::default(),
        };
        Ok((opts, learner))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s() -> Scenario {
        Scenario::builtin("paper_simple").unwrap()
    }

    #[test]
    fn episodes_auto_and_its_cap() {
        let s = s();
        assert_eq!(parse_episodes("auto").unwrap(), (None, true));
        assert_eq!(parse_episodes("12").unwrap(), (Some(12), false));
        assert!(parse_episodes("often").is_err());
        let auto = TrainRequest {
            episodes_auto: Some(true),
            ..Default::default()
        };
        let o = auto.resolve(&s).unwrap();
        assert!(o.episodes_auto);
        assert_eq!(o.episodes, crate::qlearning::AUTO_EPISODE_CAP);
        let capped = TrainRequest {
            episode_cap: Some(5000),
            ..auto.clone()
        };
        assert_eq!(capped.resolve(&s).unwrap().episodes, 5000);
        let zero = TrainRequest {
            episode_cap: Some(0),
            ..auto.clone()
        };
        assert!(zero
            .resolve(&s)
            .unwrap_err()
            .to_string()
            .contains("`episode_cap` = 0"));
        let cap_alone = TrainRequest {
            episode_cap: Some(10),
            ..Default::default()
        };
        let e = cap_alone.resolve(&s).unwrap_err().to_string();
        assert!(e.contains("only with episodes = \"auto\""), "{e}");
        let both = TrainRequest {
            episodes: Some(10),
            ..auto
        };
        assert!(both.resolve(&s).is_err());
    }

    #[test]
    fn empty_request_is_the_scenario() {
        let s = s();
        assert_eq!(
            TrainRequest::default().resolve(&s).unwrap(),
            TrainOptions::from_scenario(&s)
        );
        let (p, l) = PlanRequest::default().resolve(&s).unwrap();
        assert_eq!(p, PlanOptions::from_scenario(&s));
        assert_eq!(l, LearnerKind::Qlearning);
    }

    #[test]
    fn initial_q_by_name() {
        let s = s();
        assert_eq!(
            TrainRequest::default().resolve(&s).unwrap().initial_q,
            InitialQ::Zero
        );
        let d = TrainRequest {
            initial_q: Some("distance".into()),
            ..Default::default()
        };
        assert_eq!(d.resolve(&s).unwrap().initial_q, InitialQ::Distance);
        let bad = TrainRequest {
            initial_q: Some("optimistic".into()),
            ..Default::default()
        };
        assert_eq!(
            bad.resolve(&s).unwrap_err().to_string(),
            "invalid argument `initial_q` = optimistic: must be one of zero, distance"
        );
    }

    #[test]
    fn q_precision_by_name() {
        let s = s();
        assert_eq!(
            TrainRequest::default().resolve(&s).unwrap().q_precision,
            QPrecision::F64
        );
        let f = TrainRequest {
            q_precision: Some("f32".into()),
            ..Default::default()
        };
        assert_eq!(f.resolve(&s).unwrap().q_precision, QPrecision::F32);
        for name in ["f16", "F32", ""] {
            let bad = TrainRequest {
                q_precision: Some(name.into()),
                ..Default::default()
            };
            assert_eq!(
                bad.resolve(&s).unwrap_err().to_string(),
                format!("invalid argument `q_precision` = {name}: must be one of f64, f32")
            );
        }
    }

    #[test]
    fn assist_then_each_strategy() {
        let s = s();
        let r = TrainRequest {
            assist: Some(false),
            distance: Some(true),
            ..Default::default()
        };
        let a = r.resolve(&s).unwrap().assist;
        assert!(!a.detour && a.distance);
    }

    #[test]
    fn bad_values_name_the_field() {
        let s = s();
        for (req, text) in [
            (
                TrainRequest {
                    episodes: Some(0),
                    ..Default::default()
                },
                "invalid argument `episodes` = 0: must be an integer in 1..=4294967295",
            ),
            (
                TrainRequest {
                    seed: Some(u64::MAX as i128 + 1),
                    ..Default::default()
                },
                "invalid argument `seed` = 18446744073709551616: must be an integer >= 0",
            ),
            (
                TrainRequest {
                    max_steps_per_episode: Some(-3),
                    ..Default::default()
                },
                "invalid argument `max_steps_per_episode` = -3: must be an integer in 1..=4294967295",
            ),
        ] {
            assert_eq!(req.resolve(&s).unwrap_err().to_string(), text);
        }
        let p = PlanRequest {
            learner: Some("dqn".into()),
            ..Default::default()
        };
        assert!(p
            .resolve(&s)
            .unwrap_err()
            .to_string()
            .contains("`learner` = dqn"));
        assert_eq!(
            parse_int(SEED, "1.5").unwrap_err().to_string(),
            "invalid argument `seed` = 1.5: must be an integer >= 0"
        );
    }

    #[test]
    fn requests_round_trip_through_json() {
        let p: PlanRequest =
            serde_json::from_str(r#"{"train": {"seed": 4, "assist": false}, "learner": "bfs"}"#)
                .unwrap();
        assert_eq!(p.train.seed, Some(4));
        assert_eq!(p.train.assist, Some(false));
        let back: PlanRequest = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
        assert!(serde_json::from_str::<TrainRequest>(r#"{"sede": 4}"#).is_err());
    }
}
