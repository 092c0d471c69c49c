//! The env-step budget (`max_env_steps`), the env-step epsilon schedule and the checkpoints
//! of `train_with_checkpoints` (docs/SCENARIOS.md, "The learner: choices where the paper is
//! silent").

use super::*;
use sixaxis_core::qlearning::train_with_checkpoints;
use sixaxis_core::request::TrainRequest;
use sixaxis_core::scenario::EpsilonSchedule;

/// FNV-1a (64 bits) of the table's values as little-endian bytes (f64 or f32 as stored).
fn fingerprint(q: &QTable) -> u64 {
    let bytes: Vec<u8> = match (q.values_f64(), q.values_f32()) {
        (Some(v), _) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        (None, Some(v)) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        (None, None) => unreachable!(),
    };
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn env_steps_opts(sc: &Scenario, budget: u64, fraction: f64, seed: u64) -> Learning {
    let mut o = Learning::from_scenario(sc);
    o.max_env_steps = budget;
    o.episodes = budget as u32;
    o.epsilon_schedule = EpsilonSchedule::EnvSteps;
    o.epsilon_decay_fraction = fraction;
    o.seed = seed;
    o
}

/// One run made before the budget and the env-step schedule existed (the same call through
/// the Python bindings of that build) and what it gave: total steps, converged episode,
/// path cells, FNV-1a of the Q-table.
struct Before {
    name: &'static str,
    episodes: u32,
    seed: u64,
    assist: bool,
    precision: QPrecision,
    m: u32,
    steps: u64,
    conv: Option<u32>,
    cells: Option<usize>,
    fp: u64,
}

/// The default schedule still gives the figures of [`Before`] bit for bit.
#[test]
fn the_episode_schedule_is_bit_identical_to_before() {
    let cases = [
        Before {
            name: "paper_simple",
            episodes: 2000,
            seed: 3,
            assist: true,
            precision: QPrecision::F64,
            m: 9900,
            steps: 162_916,
            conv: Some(1999),
            cells: Some(12),
            fp: 0x223f_f8f7_4b56_3b48,
        },
        Before {
            name: "paper_simple",
            episodes: 500,
            seed: 1,
            assist: false,
            precision: QPrecision::F64,
            m: 9900,
            steps: 106_637,
            conv: None,
            cells: None,
            fp: 0x3206_43e9_734c_609a,
        },
        Before {
            name: "replan_clutter",
            episodes: 1000,
            seed: 7,
            assist: true,
            precision: QPrecision::F32,
            m: 600,
            steps: 121_717,
            conv: None,
            cells: None,
            fp: 0x4b5e_60e9_ba68_b902,
        },
    ];
    for c in cases {
        let Before {
            name,
            episodes,
            seed,
            assist,
            precision,
            m,
            steps,
            conv,
            cells,
            fp,
        } = c;
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let mut o = Learning::from_scenario(&sc);
        assert_eq!(
            (o.max_env_steps, o.epsilon_schedule),
            (0, EpsilonSchedule::Episodes)
        );
        o.episodes = episodes;
        o.seed = seed;
        o.set_assist(if assist { Assist::on() } else { Assist::off() });
        o.q_precision = precision;
        o.epsilon_decay_episodes = m;
        let r = train(&w, &o, None, None).unwrap();
        assert_eq!(r.total_steps, steps, "{name} seed {seed}");
        assert_eq!(r.converged_episode, conv, "{name} seed {seed}");
        assert_eq!(
            r.path.as_ref().map(|p| p.len()),
            cells,
            "{name} seed {seed}"
        );
        assert_eq!(fingerprint(&r.q), fp, "{name} seed {seed}");
        // A budget the run never reaches changes nothing.
        o.max_env_steps = steps + 1;
        let b = train(&w, &o, None, None).unwrap();
        assert_eq!((b.total_steps, fingerprint(&b.q)), (steps, fp));
    }
}

#[test]
fn a_budget_stops_at_exactly_max_env_steps() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut cut_mid_episode = 0;
    for schedule in [EpsilonSchedule::Episodes, EpsilonSchedule::EnvSteps] {
        for budget in [1u64, 999, 1000, 1001, 12_345, 30_000] {
            let mut o = env_steps_opts(&sc, budget, 0.99, 5);
            o.epsilon_schedule = schedule;
            let r = train(&w, &o, None, None).unwrap();
            assert_eq!(r.total_steps, budget, "{schedule} {budget}");
            let sum: u64 = r.steps_per_episode.iter().map(|&k| k as u64).sum();
            assert_eq!(sum, budget);
            let (last, reached) = (
                *r.steps_per_episode.last().unwrap(),
                *r.reached_per_episode.last().unwrap(),
            );
            if !reached && last < o.max_steps_per_episode {
                cut_mid_episode += 1;
            }
        }
    }
    assert!(
        cut_mid_episode >= 4,
        "{cut_mid_episode} runs cut mid-episode"
    );
    // The episode cap still applies: 3 episodes end before a large budget.
    let mut o = env_steps_opts(&sc, 1_000_000, 0.99, 5);
    o.episodes = 3;
    let r = train(&w, &o, None, None).unwrap();
    assert_eq!(r.steps_per_episode.len(), 3);
    assert!(r.total_steps < 1_000_000);
}

#[test]
fn epsilon_falls_over_env_steps_to_zero_at_d() {
    let sc = scenario("paper_simple");
    let o = env_steps_opts(&sc, 10_000, 0.99, 0);
    assert_eq!(o.epsilon_decay_steps(), 9900.0);
    assert_eq!(o.epsilon_at_step(0), 0.1);
    assert!((o.epsilon_at_step(4950) - 0.05).abs() < 1e-15);
    assert!(o.epsilon_at_step(9899) > 0.0);
    assert_eq!(o.epsilon_at_step(9900), 0.0);
    assert_eq!(o.epsilon_at_step(50_000), 0.0);
    let none = Learning {
        epsilon_decay_fraction: 0.0,
        ..o
    };
    assert_eq!(none.epsilon_at_step(0), 0.0);
    // The episode schedule ignores these fields.
    let episodes = Learning {
        epsilon_schedule: EpsilonSchedule::Episodes,
        ..o
    };
    assert_eq!(episodes.epsilon(0), 0.1);
}

/// The learner of the module docs with the env-step schedule and the budget, written
/// plainly with `GridWorld::step` and `q_update`.
fn reference_env_steps(world: &GridWorld, o: &Learning) -> (QTable, Vec<u32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let mut q = QTable::zeros(world.num_states());
    let mut steps_per_episode = Vec::new();
    let mut t = 0u64;
    'episodes: for _ in 0..o.episodes {
        let mut s = world.start();
        let mut last = None;
        let mut steps = 0;
        while steps < o.max_steps_per_episode {
            let threshold = (o.epsilon_at_step(t) * 4_294_967_296.0).ceil() as u64;
            let a = if threshold > 0 && (rng.next_u32() as u64) < threshold {
                rng.random_range(0..6u32) as usize
            } else {
                let m = q.max_value(s);
                let ties: Vec<usize> = (0..6).filter(|&a| q.get(s, a) == m).collect();
                if ties.len() == 1 {
                    ties[0]
                } else {
                    ties[rng.random_range(0..ties.len() as u32) as usize]
                }
            };
            let tr = world.step(s, a, last, o.assist());
            q_update(&mut q, s, a, &tr, o.alpha, o.gamma);
            last = tr.collided.then_some(a);
            s = tr.next;
            steps += 1;
            t += 1;
            if t == o.max_env_steps {
                steps_per_episode.push(steps);
                break 'episodes;
            }
            if tr.reached {
                break;
            }
        }
        steps_per_episode.push(steps);
    }
    (q, steps_per_episode)
}

#[test]
fn the_env_step_schedule_is_the_plain_reference() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    for (budget, fraction, seed, epsilon_start) in [
        (20_000u64, 0.99, 0u64, 0.1),
        (7_777, 0.5, 3, 0.6),
        (5_000, 0.0, 1, 0.3),
    ] {
        let mut o = env_steps_opts(&sc, budget, fraction, seed);
        o.epsilon_start = epsilon_start;
        let fast = train(&w, &o, None, None).unwrap();
        let (q, steps) = reference_env_steps(&w, &o);
        assert_eq!(fast.q.values(), q.values(), "budget {budget}");
        assert_eq!(fast.steps_per_episode, steps, "budget {budget}");
        assert_eq!(fast.path, greedy_path(&w, &q, o.max_steps_per_episode));
    }
}

/// A checkpoint's path is the final path of the same run stopped there: `max_env_steps` =
/// the checkpoint, the same schedule (for `env_steps`, the same D: the fraction scaled; the
/// values are chosen so that D is exact).
#[test]
fn checkpoints_equal_runs_stopped_there() {
    for name in ["paper_simple", "replan_clutter"] {
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let budget = 200_000u64;
        let cps = [
            1u64, 6_250, 50_000, 80_000, 100_000, 128_000, 160_000, 200_000,
        ];
        for schedule in [EpsilonSchedule::Episodes, EpsilonSchedule::EnvSteps] {
            let mut o = env_steps_opts(&sc, budget, 0.5, 11);
            o.epsilon_schedule = schedule;
            o.epsilon_decay_episodes = 1500;
            let with = train_with_checkpoints(&w, &o, None, None, &cps).unwrap();
            let without = train(&w, &o, None, None).unwrap();
            // Recording changes nothing of the run.
            assert_eq!(with.q.values(), without.q.values());
            assert_eq!(with.steps_per_episode, without.steps_per_episode);
            assert_eq!(with.path, without.path);
            assert!(without.checkpoints.is_empty());
            assert_eq!(with.checkpoints.len(), cps.len());
            let mut reached = 0;
            let mut last_time = 0.0;
            for (cp, &c) in with.checkpoints.iter().zip(&cps) {
                assert_eq!(cp.env_steps, c);
                let mut stop = o;
                stop.max_env_steps = c;
                stop.epsilon_decay_fraction = 100_000.0 / c as f64;
                assert_eq!(stop.epsilon_decay_steps(), o.epsilon_decay_steps());
                let again = train(&w, &stop, None, None).unwrap();
                assert_eq!(cp.path, again.path, "{name} {schedule} at {c}");
                assert_eq!(cp.episode as usize + 1, again.steps_per_episode.len());
                assert!(cp.wall_time_s >= last_time);
                last_time = cp.wall_time_s;
                assert!(cp.cpu_time_s.is_some_and(|s| s >= 0.0));
                reached += cp.path.is_some() as usize;
            }
            assert_eq!(with.checkpoints.last().unwrap().path, with.path);
            // The curve is not trivial: the first checkpoint has no path, a later one has.
            assert!(with.checkpoints[0].path.is_none());
            assert!(
                reached > 0,
                "{name} {schedule}: no checkpoint reached the target"
            );
            // Deterministic: the same call records the same checkpoints.
            let twice = train_with_checkpoints(&w, &o, None, None, &cps).unwrap();
            for (a, b) in with.checkpoints.iter().zip(&twice.checkpoints) {
                assert_eq!(
                    (a.env_steps, a.episode, &a.path),
                    (b.env_steps, b.episode, &b.path)
                );
            }
        }
    }
}

#[test]
fn bad_budgets_and_checkpoints_are_errors_naming_them() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let err = |r: TrainRequest| r.resolve(&sc).unwrap_err().to_string();
    assert_eq!(
        err(TrainRequest::default().with("epsilon_schedule", "env_steps")),
        "invalid argument `epsilon_schedule` = env_steps: needs a budget: max_env_steps >= 1"
    );
    assert!(
        err(TrainRequest::default().with("epsilon_schedule", "steps")).starts_with(
            "invalid argument `epsilon_schedule` = steps: must be one of episodes, env_steps"
        )
    );
    assert!(err(TrainRequest::default().with("max_env_steps", -1))
        .starts_with("invalid argument `max_env_steps` = -1"));
    assert!(
        err(TrainRequest::default().with("epsilon_decay_fraction", -0.5))
            .starts_with("invalid argument `epsilon_decay_fraction` = -0.5")
    );
    let auto = TrainRequest::default()
        .with("episodes", "auto")
        .with("max_env_steps", 100)
        .with("epsilon_schedule", "env_steps");
    assert!(err(auto).contains("`epsilon_schedule` = env_steps: does not combine"));
    let ok = TrainRequest::default()
        .with("max_env_steps", 100)
        .with("epsilon_schedule", "env_steps")
        .resolve(&sc)
        .unwrap();
    assert_eq!(ok.epsilon_decay_steps(), 99.0);
    let cp_err = |cps: &[u64]| {
        train_with_checkpoints(&w, &ok, None, None, cps)
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        cp_err(&[0]),
        "invalid argument `checkpoints` = 0: every checkpoint must be >= 1 env step"
    );
    assert_eq!(
        cp_err(&[5, 5]),
        "invalid argument `checkpoints` = 5: checkpoints must increase (one after 5)"
    );
    assert_eq!(
        cp_err(&[50, 101]),
        "invalid argument `checkpoints` = 101: is beyond max_env_steps = 100"
    );
    // Without a budget a checkpoint past the run's end is simply not reached.
    let mut short = Learning::from_scenario(&sc);
    short.episodes = 2;
    let r = train_with_checkpoints(&w, &short, None, None, &[1, 10_000_000]).unwrap();
    assert_eq!(r.checkpoints.len(), 1);
    assert_eq!(
        (r.checkpoints[0].env_steps, r.checkpoints[0].episode),
        (1, 0)
    );
}
