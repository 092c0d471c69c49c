//! Algorithm 2 (learn, plan poses, re-plan) and the scenario generator. Every plan is
//! re-checked without the planner (`common::check_poses`).

mod common;

use common::check_poses_nd;
use sixaxis_core::generator::{generate, GeneratorOptions};
use sixaxis_core::names::expand_names;
use sixaxis_core::planner::PosePoint;
use sixaxis_core::replanning::{plan, LearnedPath, PlanOptions, PlanResult};
use sixaxis_core::scenario::PoseSearchMode;
use sixaxis_core::{GridWorld, PosePlanner, Scenario};

fn run(s: &Scenario, seed: u64) -> PlanResult {
    let mut o = PlanOptions::from_scenario(s);
    o.train.seed = seed;
    plan(s, &o, None, None).unwrap()
}

/// Re-check a successful result's poses independently of the planner.
fn check_result(s: &Scenario, r: &PlanResult) {
    assert!(r.success, "{:?}", r.failure);
    assert_eq!(r.failure, None);
    assert_eq!(r.path.first(), Some(&s.start));
    assert_eq!(r.path.last(), Some(&s.target));
    assert_eq!(r.poses_rad.len(), r.path.len());
    assert_eq!(r.orientations_rpy_deg.len(), r.path.len());
    for w in r.path.windows(2) {
        let d: i32 = (0..3).map(|i| (w[0][i] - w[1][i]).abs()).sum();
        assert_eq!(d, 1, "path steps one cell at a time: {w:?}");
        assert!(
            !s.obstacles.contains(&w[1]),
            "path enters an obstacle: {:?}",
            w[1]
        );
        assert!(
            !r.added_obstacles.contains(&w[1]),
            "path enters an added obstacle"
        );
    }
    let points: Vec<PosePoint> = r
        .path
        .iter()
        .zip(&r.poses_rad)
        .zip(&r.orientations_rpy_deg)
        .map(|((&cell, &joints_rad), &orientation_rpy_deg)| PosePoint {
            cell,
            joints_rad,
            orientation_rpy_deg,
        })
        .collect();
    let n_d = r.rounds.last().expect("a round").orientation_divisions;
    check_poses_nd(s, &r.path, &points, n_d);
    let m = r.min_centre_clearance_cells.expect("a motion");
    assert!(m > s.arm_safe_distance, "eq. 11 clearance {m}");
    assert!(r.min_cube_distance_mm.expect("a motion") >= 0.0);
}

fn without_times(mut r: PlanResult) -> PlanResult {
    r.wall_time_s = 0.0;
    for round in &mut r.rounds {
        round.learning_time_s = 0.0;
    }
    r
}

#[test]
fn paper_simple_needs_no_replan() {
    let s = Scenario::builtin("paper_simple").unwrap();
    for seed in 0..3 {
        let r = run(&s, seed);
        check_result(&s, &r);
        assert_eq!(r.replans, 0);
        assert!(r.added_obstacles.is_empty());
        assert_eq!(r.path.len() - 1, 9, "the learned path is as short as BFS's");
    }
}

#[test]
fn same_seed_same_plan() {
    let s = Scenario::builtin("replan_clutter").unwrap();
    let a = without_times(run(&s, 4));
    let b = without_times(run(&s, 4));
    assert_eq!(a, b);
}

#[test]
fn replan_scenario_gets_a_replan_and_succeeds() {
    let s = Scenario::builtin("replan_clutter").unwrap();
    for seed in 0..3 {
        let r = run(&s, seed);
        check_result(&s, &r);
        assert!(r.replans >= 1, "seed {seed}: no re-plan");
        assert_eq!(r.added_obstacles.len() as u32, r.replans);
        assert_eq!(r.rounds.len() as u32, r.replans + 1);
        // Every round but the last stopped at the point it recorded (or the one before the target).
        for (round, added) in r.rounds.iter().zip(&r.added_obstacles) {
            let (index, cell) = round.blocked_at.expect("a re-planned round was blocked");
            let path = round.path.as_ref().unwrap();
            assert!(*added == cell || (cell == s.target && *added == path[index - 1]));
        }
        assert_eq!(r.rounds.last().unwrap().blocked_at, None);
    }
}

#[test]
fn search_modes_agree_where_the_greedy_pass_succeeds() {
    // Backtracking only differs from the paper's greedy pass after a dead end: on
    // paper_simple (no dead end) both give the same path and poses.
    let s = Scenario::builtin("paper_simple").unwrap();
    assert_eq!(s.planning.mode, PoseSearchMode::Paper);
    let mut bt = s.clone();
    bt.planning.mode = PoseSearchMode::Backtracking;
    let (a, b) = (run(&s, 0), run(&bt, 0));
    assert_eq!((&a.path, &a.poses_rad), (&b.path, &b.poses_rad));
    assert_eq!(a.rounds[0].mode, PoseSearchMode::Paper);
    assert_eq!(b.rounds[0].mode, PoseSearchMode::Backtracking);
}

/// Table 3 with the paper's Algorithm 1 as written (the default of paper_complex): one
/// re-plan at n_d = 8, then success at n_d = 16. Our backtracking needs none; the greedy
/// pass without the n_d change fails.
#[test]
fn paper_complex_modes_give_the_documented_outcomes() {
    let s = Scenario::builtin("paper_complex").unwrap();
    assert_eq!(s.planning.mode, PoseSearchMode::Paper);
    for seed in 0..3 {
        let r = run(&s, seed);
        check_result(&s, &r);
        assert_eq!(r.replans, 1, "seed {seed}");
        assert_eq!(r.added_obstacles, [[0, 2, 0]], "seed {seed}");
        let nd: Vec<u32> = r.rounds.iter().map(|x| x.orientation_divisions).collect();
        assert_eq!(nd, [8, 16], "seed {seed}");
        assert!(r.rounds.iter().all(|x| x.mode == PoseSearchMode::Paper));
        assert_eq!(r.rounds[0].path.as_ref().unwrap().len() - 1, 9);
        assert_eq!(r.path.len() - 1, 11);
    }
    let mut bt = s.clone();
    bt.planning.mode = PoseSearchMode::Backtracking;
    let r = run(&bt, 0);
    check_result(&bt, &r);
    assert_eq!(r.replans, 0);
    let mut fixed = s.clone();
    fixed.planning.orientation_divisions_growth = 1;
    let r = run(&fixed, 0);
    assert!(!r.success);
    assert!(r.rounds.iter().all(|x| x.orientation_divisions == 8));
    assert_eq!(r.min_cube_distance_mm, None);
}

#[test]
fn unreachable_target_is_a_clear_failure() {
    // (0, 5, 0): free for the terminal, but no arm pose reaches it with clearance.
    let mut s = Scenario::builtin("paper_simple").unwrap();
    s.target = [0, 5, 0];
    s.validate().unwrap();
    let planner = PosePlanner::from_scenario(&s);
    assert!(!planner.cell_reachable(s.target));
    let r = run(&s, 0);
    assert!(!r.success);
    let why = r.failure.expect("a reason");
    assert!(why.contains("could not be reached"), "{why}");
    assert!(r.replans <= s.planning.max_replans);
    assert!(!r.added_obstacles.is_empty());
    assert!(why.contains(&format!(
        "({}, {}, {})",
        r.added_obstacles[0][0], r.added_obstacles[0][1], r.added_obstacles[0][2]
    )));
}

#[test]
fn replan_cap_ends_the_loop() {
    let mut s = Scenario::builtin("replan_clutter").unwrap();
    s.planning.max_replans = 0;
    let r = run(&s, 0);
    assert!(!r.success);
    assert_eq!(r.replans, 0);
    let why = r.failure.unwrap();
    assert!(why.starts_with("re-plan cap (0) reached"), "{why}");
    assert_eq!(r.added_obstacles.len(), 1);
}

#[test]
fn unlearned_path_is_a_clear_failure() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let mut o = PlanOptions::from_scenario(&s);
    o.train.episodes = 1;
    let r = plan(&s, &o, None, None).unwrap();
    assert!(!r.success);
    assert!(r
        .failure
        .unwrap()
        .contains("does not reach the target after 1 episodes"));
}

#[test]
fn unlearned_path_within_an_env_step_budget_names_the_budget() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let mut o = PlanOptions::from_scenario(&s);
    o.train.max_env_steps = 5;
    let r = plan(&s, &o, None, None).unwrap();
    assert!(!r.success);
    let why = r.failure.unwrap();
    assert!(
        why.contains("does not reach the target after its budget of 5 env steps"),
        "{why}"
    );
}

#[test]
fn generator_guarantees_hold_over_many_seeds() {
    let opts = GeneratorOptions::default();
    for seed in 0..40 {
        let s = generate(&opts, seed).unwrap();
        assert_eq!(
            s,
            generate(&opts, seed).unwrap(),
            "seed {seed}: not deterministic"
        );
        s.validate().unwrap();
        assert_eq!(s.name, format!("generated:{seed}"));
        assert_eq!(Scenario::load(&s.name).unwrap(), s);
        let world = GridWorld::new(&s).unwrap();
        assert!(
            world.shortest_path().is_some(),
            "seed {seed}: start and target not connected"
        );
        let planner = PosePlanner::from_scenario(&s);
        assert!(planner.cell_reachable(s.start), "seed {seed}: start");
        assert!(planner.cell_reachable(s.target), "seed {seed}: target");
        let expected = (opts.density * s.bounds.volume() as f64).round() as usize;
        assert_eq!(s.obstacles.len(), expected);
        let d: f64 = (0..3)
            .map(|i| ((s.start[i] - s.target[i]) as f64).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d >= opts.min_start_target_distance);
    }
    assert_ne!(generate(&opts, 1).unwrap(), generate(&opts, 2).unwrap());
}

#[test]
fn generator_rejects_bad_options_and_expands_names() {
    let bad = GeneratorOptions {
        density: 0.9,
        ..GeneratorOptions::default()
    };
    assert!(generate(&bad, 0)
        .unwrap_err()
        .to_string()
        .contains("density"));
    assert_eq!(
        expand_names("paper_simple, generated:2..4").unwrap(),
        ["paper_simple", "generated:2", "generated:3", "generated:4"]
    );
    assert!(expand_names("generated:5..2").is_err());
    assert!(Scenario::load("generated:x")
        .unwrap_err()
        .to_string()
        .contains("generated:x"));
}

#[test]
fn default_learner_is_the_tabular_q_learner_bit_for_bit() {
    use sixaxis_core::replanning::QLearner;
    let s = Scenario::load("replan_clutter").unwrap();
    let o = PlanOptions::from_scenario(&s);
    let default = without_times(plan(&s, &o, None, None).unwrap());
    let mut q = QLearner { opts: o.train };
    let explicit = without_times(plan(&s, &o, Some(&mut q), None).unwrap());
    assert_eq!(default, explicit);
    assert!(default.replans >= 1);
    assert!(default
        .rounds
        .iter()
        .all(|r| r.length_converged_episode.is_some()));
}

#[test]
fn bfs_learner_plans_each_round_on_that_rounds_world() {
    use sixaxis_core::replanning::BfsLearner;
    let s = Scenario::load("replan_clutter").unwrap();
    let o = PlanOptions::from_scenario(&s);
    let r = plan(&s, &o, Some(&mut BfsLearner), None).unwrap();
    check_result(&s, &r);
    for round in &r.rounds {
        let added = &r.added_obstacles[..round.added_obstacles];
        let world = GridWorld::with_extra_obstacles(&s, added).unwrap();
        assert_eq!(round.path, world.shortest_path());
        assert_eq!(round.total_steps, 0);
    }
}

/// A learner that returns the same result every round, to see what the core makes of it.
struct Returns(LearnedPath);

impl Returns {
    /// A fixed path.
    fn path(path: Vec<sixaxis_core::Cell>) -> Self {
        Returns(LearnedPath {
            path: Some(path),
            ..Default::default()
        })
    }
}

impl sixaxis_core::replanning::PathLearner for Returns {
    fn learn_path(
        &mut self,
        _world: &GridWorld,
        _round: &sixaxis_core::replanning::Round<'_>,
    ) -> sixaxis_core::Result<LearnedPath> {
        Ok(self.0.clone())
    }
}

#[test]
fn invalid_learned_paths_are_rejected_with_the_rule_they_break() {
    let s = Scenario::load("paper_simple").unwrap();
    let o = PlanOptions::from_scenario(&s);
    let good = GridWorld::new(&s).unwrap().shortest_path().unwrap();
    let obstacle = s.obstacles[0];
    let cases = [
        (good[1..].to_vec(), "must start at the start cell"),
        (
            good[..good.len() - 1].to_vec(),
            "must end at the target cell",
        ),
        (
            [&good[..1], &good[2..]].concat(),
            "is not a move to one of the six neighbouring cells",
        ),
        (vec![s.start, obstacle, s.target], "is an obstacle"),
        (Vec::new(), "empty path"),
    ];
    for (path, words) in cases {
        let e = plan(&s, &o, Some(&mut Returns::path(path)), None).unwrap_err();
        let text = e.to_string();
        assert!(text.contains(words), "{text}");
        assert!(text.starts_with("invalid argument `path`"), "{text}");
    }
    let ok = plan(&s, &o, Some(&mut Returns::path(good.clone())), None).unwrap();
    assert!(ok.success && ok.path == good);
}

#[test]
fn a_learners_own_reason_for_no_path_is_the_failure_with_its_round() {
    let s = Scenario::load("paper_simple").unwrap();
    let o = PlanOptions::from_scenario(&s);
    let refuses = |reason: Option<&str>| {
        Returns(LearnedPath {
            no_path_reason: reason.map(str::to_string),
            ..Default::default()
        })
    };
    let own = plan(
        &s,
        &o,
        Some(&mut refuses(Some("the start is blocked"))),
        None,
    )
    .unwrap();
    assert!(!own.success);
    assert_eq!(
        own.failure.as_deref(),
        Some("the start is blocked (round 0)")
    );
    let default = plan(&s, &o, Some(&mut refuses(None)), None).unwrap();
    assert_eq!(
        default.failure.as_deref(),
        Some("the path learner found no path to the target (round 0)")
    );
    // A reason beside a path is not read: the path is planned.
    let good = GridWorld::new(&s).unwrap().shortest_path().unwrap();
    let mut both = Returns::path(good);
    both.0.no_path_reason = Some("unused".into());
    let ok = plan(&s, &o, Some(&mut both), None).unwrap();
    assert!(ok.success && ok.failure.is_none());
}
