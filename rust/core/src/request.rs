//! Requests: what a caller asks of a training or planning run, as options by key that
//! override the scenario's settings, resolved in one place.
//!
//! Entry points:
//! - [`TrainRequest`] — options of a training run ([`train_options`]: the keys of
//!   [`Learning::OPTIONS`] plus `assist` and `episode_cap`); [`TrainRequest::resolve`]
//!   against a scenario gives the [`Learning`] of [`crate::qlearning::train`].
//! - [`PlanRequest`] — the training options plus the re-plan cap and the path learner
//!   ([`plan_options`]); [`PlanRequest::resolve`] gives the [`PlanOptions`] and
//!   [`LearnerKind`] of [`crate::replanning::plan`].
//! - [`train_options`] / [`plan_options`] — what each key is: domain, unit, doc, the scenario
//!   field it overrides. The `sixaxis` CLI builds its flags from them and the Python bindings
//!   their keywords, so both take the same values, use the same defaults and give the same
//!   error text (named after the key: `seed`, `episodes`, ...).
//!
//! A key left out takes the scenario's value. Keys apply in the table's order: `assist`
//! (both eqs. 9 and 10 on or off) before `detour` and `distance` (each on its own), and
//! `episodes` (a number, or `"auto"`) before `episode_cap` (the cap of `"auto"`, an error
//! otherwise).
//!
//! ```
//! use sixaxis_core::request::{PlanRequest, TrainRequest};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let req = TrainRequest::default().with("seed", 3).with("detour", false);
//! let opts = req.resolve(&s).unwrap();
//! assert_eq!((opts.seed, opts.episodes), (3, 10_000));
//! assert!(!opts.assist_detour && opts.assist_distance);
//! let bad = TrainRequest::default().with("seed", -1);
//! assert_eq!(
//!     bad.resolve(&s).unwrap_err().to_string(),
//!     "invalid argument `seed` = -1: must be an integer >= 0"
//! );
//! assert!(PlanRequest::default().resolve(&s).is_ok());
//! ```

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::options::{
    apply, named_enum, reject_unknown, Domain, FromOption, OptionInfo, OptionSpec, OptionValue,
    Options,
};
use crate::replanning::PlanOptions;
use crate::scenario::{Learning, Scenario, AUTO_EPISODE_CAP};

named_enum! {
    /// The path learners [`PlanRequest`]'s `learner` can name.
    pub enum LearnerKind (default Qlearning) {
        /// Tabular Q-learning, the paper's ([`crate::replanning::QLearner`]).
        Qlearning = "qlearning",
        /// The breadth-first shortest path ([`crate::replanning::BfsLearner`]).
        Bfs = "bfs",
    }
}

/// `assist`: both strategies at once (a request key with no scenario field of its own).
static ASSIST: OptionSpec<Learning> = OptionSpec {
    info: OptionInfo {
        key: "assist",
        field: "",
        domain: Domain::Bool,
        unit: "",
        doc: "Both assisted strategies (eqs. 9 and 10) on or off; `detour` and `distance` then switch one of them.",
    },
    get: |o| OptionValue::Bool(o.assist_detour && o.assist_distance),
    set: |o, key, v| {
        let a = bool::from_option(key, &Domain::Bool, v)?;
        o.assist_detour = a;
        o.assist_distance = a;
        Ok(())
    },
};

/// `episode_cap`: the cap of `episodes = "auto"`.
static EPISODE_CAP: OptionSpec<Learning> = OptionSpec {
    info: OptionInfo {
        key: "episode_cap",
        field: "",
        domain: Domain::u32_from(1),
        unit: "episodes",
        doc: "Episode cap of `episodes = \"auto\"` (default 1000000); only with `episodes = \"auto\"`.",
    },
    get: |o| {
        OptionValue::Int(if o.episodes_auto {
            o.episodes
        } else {
            AUTO_EPISODE_CAP
        } as i128)
    },
    set: |o, key, v| {
        let cap = u32::from_option(key, &Domain::u32_from(1), v)?;
        if !o.episodes_auto {
            return Err(Error::argument(
                key,
                cap,
                "applies only with episodes = \"auto\"",
            ));
        }
        o.episodes = cap;
        Ok(())
    },
};

/// The options of a training run, in the order they apply: `assist`, every keyed option of
/// [`Learning::OPTIONS`], `episode_cap`.
pub fn train_table() -> Vec<&'static OptionSpec<Learning>> {
    std::iter::once(&ASSIST)
        .chain(Learning::OPTIONS.iter().filter(|s| !s.info.key.is_empty()))
        .chain(std::iter::once(&EPISODE_CAP))
        .collect()
}

/// What each option of a training run is (see [`train_table`]).
pub fn train_options() -> Vec<OptionInfo> {
    train_table().iter().map(|s| s.info).collect()
}

/// The options Algorithm 2 adds to a training run's.
static PLAN_ONLY: [OptionSpec<(PlanOptions, LearnerKind)>; 2] = [
    OptionSpec {
        info: OptionInfo {
            key: "max_replans",
            field: "planning.max_replans",
            domain: Domain::u32_from(0),
            unit: "re-plans",
            doc: "Re-plans allowed before Algorithm 2 gives up.",
        },
        get: |(p, _)| OptionValue::Int(p.max_replans as i128),
        set: |(p, _), key, v| {
            p.max_replans = u32::from_option(key, &Domain::u32_from(0), v)?;
            Ok(())
        },
    },
    OptionSpec {
        info: OptionInfo {
            key: "learner",
            field: "",
            domain: LearnerKind::DOMAIN,
            unit: "",
            doc: "The path learner of every round: `qlearning` (the paper's) or `bfs` (the shortest path); from Python also a callable.",
        },
        get: |(_, l)| OptionValue::Text(l.name().to_string()),
        set: |(_, l), key, v| {
            *l = LearnerKind::from_option(key, &LearnerKind::DOMAIN, v)?;
            Ok(())
        },
    },
];

/// What each option of an Algorithm 2 run is: [`train_options`], `max_replans`, `learner`.
pub fn plan_options() -> Vec<OptionInfo> {
    let mut all = train_options();
    all.extend(PLAN_ONLY.iter().map(|s| s.info));
    all
}

/// The value of every option of [`plan_options`] in scenario `s` (by key): what a request
/// that leaves the key out gets.
pub fn option_values(s: &Scenario) -> Vec<(&'static str, OptionValue)> {
    let mut out: Vec<(&'static str, OptionValue)> = train_table()
        .iter()
        .map(|spec| (spec.info.key, (spec.get)(&s.learning)))
        .collect();
    let plan = (PlanOptions::from_scenario(s), LearnerKind::default());
    out.extend(
        PLAN_ONLY
            .iter()
            .map(|spec| (spec.info.key, (spec.get)(&plan))),
    );
    out
}

/// Options of a training run by key; a key left out takes the scenario's `learning` value.
/// Serialises as a JSON object: `{"seed": 3, "episodes": "auto"}`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct TrainRequest(pub Options);

impl TrainRequest {
    /// This request with `key` set to `value`.
    pub fn with(mut self, key: &str, value: impl Into<OptionValue>) -> Self {
        self.0.insert(key.to_string(), value.into());
        self
    }

    /// The scenario's learning options with these overrides, every range checked.
    pub fn resolve(&self, s: &Scenario) -> Result<Learning> {
        let mut opts = s.learning;
        apply(&train_table(), &self.0, &mut opts)?;
        opts.validate()?;
        Ok(opts)
    }
}

/// Options of an Algorithm 2 run by key: those of [`TrainRequest`] for every round, plus
/// `max_replans` and `learner` ([`plan_options`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct PlanRequest(pub Options);

impl PlanRequest {
    /// This request with `key` set to `value`.
    pub fn with(mut self, key: &str, value: impl Into<OptionValue>) -> Self {
        self.0.insert(key.to_string(), value.into());
        self
    }

    /// The scenario's planning options with these overrides, and the learner asked for.
    pub fn resolve(&self, s: &Scenario) -> Result<(PlanOptions, LearnerKind)> {
        let plan_only: Vec<&OptionSpec<(PlanOptions, LearnerKind)>> = PLAN_ONLY.iter().collect();
        let is_plan = |k: &str| plan_only.iter().any(|p| p.info.key == k);
        let (mine, train): (Options, Options) =
            self.0.clone().into_iter().partition(|(k, _)| is_plan(k));
        let keys: Vec<&str> = plan_options().iter().map(|i| i.key).collect();
        reject_unknown(&keys, &self.0)?;
        let mut target = (PlanOptions::from_scenario(s), LearnerKind::default());
        target.0.train = TrainRequest(train).resolve(s)?;
        apply(&plan_only, &mine, &mut target)?;
        Ok(target)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s() -> Scenario {
        Scenario::builtin("paper_simple").unwrap()
    }

    fn err(r: &TrainRequest) -> String {
        r.resolve(&s()).unwrap_err().to_string()
    }

    #[test]
    fn episodes_auto_and_its_cap() {
        let s = s();
        let auto = TrainRequest::default().with("episodes", "auto");
        let o = auto.resolve(&s).unwrap();
        assert!(o.episodes_auto);
        assert_eq!(o.episodes, AUTO_EPISODE_CAP);
        let capped = auto.clone().with("episode_cap", 5000);
        assert_eq!(capped.resolve(&s).unwrap().episodes, 5000);
        assert!(err(&auto.clone().with("episode_cap", 0)).contains("`episode_cap` = 0"));
        let e = err(&TrainRequest::default().with("episode_cap", 10));
        assert!(e.contains("only with episodes = \"auto\""), "{e}");
        assert_eq!(
            err(&TrainRequest::default().with("episodes", "often")),
            "invalid argument `episodes` = often: must be an integer in 1..=4294967295 or \"auto\""
        );
    }

    #[test]
    fn empty_request_is_the_scenario() {
        let s = s();
        assert_eq!(TrainRequest::default().resolve(&s).unwrap(), s.learning);
        let (p, l) = PlanRequest::default().resolve(&s).unwrap();
        assert_eq!(p, PlanOptions::from_scenario(&s));
        assert_eq!(l, LearnerKind::Qlearning);
    }

    #[test]
    fn choices_by_name() {
        let s = s();
        let d = TrainRequest::default().with("initial_q", "distance");
        assert_eq!(
            d.resolve(&s).unwrap().initial_q,
            crate::scenario::InitialQ::Distance
        );
        assert_eq!(
            err(&TrainRequest::default().with("initial_q", "optimistic")),
            "invalid argument `initial_q` = optimistic: must be one of zero, distance"
        );
        for name in ["f16", "F32", ""] {
            assert_eq!(
                err(&TrainRequest::default().with("q_precision", name)),
                format!("invalid argument `q_precision` = {name}: must be one of f64, f32")
            );
        }
    }

    #[test]
    fn assist_then_each_strategy() {
        let r = TrainRequest::default()
            .with("distance", true)
            .with("assist", false);
        let a = r.resolve(&s()).unwrap().assist();
        assert!(!a.detour && a.distance);
    }

    #[test]
    fn bad_values_name_the_field() {
        for (req, text) in [
            (
                TrainRequest::default().with("episodes", 0),
                "invalid argument `episodes` = 0: must be an integer in 1..=4294967295 or \"auto\"",
            ),
            (
                TrainRequest(
                    [("seed".to_string(), OptionValue::Int(u64::MAX as i128 + 1))].into(),
                ),
                "invalid argument `seed` = 18446744073709551616: must be an integer >= 0",
            ),
            (
                TrainRequest::default().with("max_steps_per_episode", -3),
                "invalid argument `max_steps_per_episode` = -3: must be an integer in 1..=4294967295",
            ),
            (
                TrainRequest::default().with("alpha", 0.0),
                "invalid argument `alpha` = 0: must be a number in (0, 1]",
            ),
            (
                TrainRequest::default().with("seed", true),
                "invalid argument `seed` = true: must be an integer >= 0",
            ),
        ] {
            assert_eq!(err(&req), text);
        }
        let e = err(&TrainRequest::default().with("sede", 4));
        assert!(e.starts_with("invalid argument `sede` = 4: is no option here; the options are assist, episodes, seed"), "{e}");
        let p = PlanRequest::default().with("learner", "dqn");
        let e = p.resolve(&s()).unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid argument `learner` = dqn: must be one of qlearning, bfs"
        );
        let e = PlanRequest::default()
            .with("replans", 2)
            .resolve(&s())
            .unwrap_err()
            .to_string();
        assert!(e.contains("max_replans, learner"), "{e}");
    }

    #[test]
    fn every_learning_field_is_checked_with_the_request_words() {
        // A scenario with alpha out of range is refused with the same domain words as a
        // request, naming the scenario field.
        let mut s = s();
        s.learning.alpha = 2.0;
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "invalid scenario: field `learning.alpha` = 2: must be a number in (0, 1]"
        );
    }

    #[test]
    fn requests_round_trip_through_json() {
        let p: PlanRequest =
            serde_json::from_str(r#"{"seed": 4, "assist": false, "learner": "bfs"}"#).unwrap();
        assert_eq!(p.0["seed"], OptionValue::Int(4));
        let (opts, l) = p.resolve(&s()).unwrap();
        assert_eq!((opts.train.seed, l), (4, LearnerKind::Bfs));
        let back: PlanRequest = serde_json::from_str(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
    }

    #[test]
    fn every_key_is_documented_once() {
        let keys: Vec<&str> = plan_options().iter().map(|i| i.key).collect();
        let mut unique = keys.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), keys.len(), "{keys:?}");
        for i in plan_options() {
            assert!(!i.doc_line().is_empty(), "{} has no doc", i.key);
        }
        assert!(!keys.contains(&""));
    }
}
