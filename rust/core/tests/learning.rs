//! Grid world rewards (eqs. 5, 9, 10), the Q-update (eq. 6), the learner (eqs. 7-8),
//! breadth-first shortest paths and Q-table files.
//!
//! Run with `-- --nocapture` to see the reported figures (BFS length, learned path length,
//! converged episodes).

use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sixaxis_core::grid::{opposite, Assist, GridWorld, Transition, ACTIONS};
use sixaxis_core::qlearning::{greedy_path, q_update, train, Learning, QTable};
use sixaxis_core::scenario::{Bounds, QPrecision};
use sixaxis_core::{Cell, Error, Scenario};

const PX: usize = 0;
const MX: usize = 1;
const PY: usize = 2;
const MY: usize = 3;
const PZ: usize = 4;
const MZ: usize = 5;

fn scenario(name: &str) -> Scenario {
    Scenario::builtin(name).unwrap()
}

fn world(name: &str) -> GridWorld {
    GridWorld::new(&scenario(name)).unwrap()
}

/// A 3x1x1 corridor x = 0..=2 at (y, z) = (-2, 4) (the start cell of the paper's arm, so
/// the scenario still validates), start x = 0, target x = 2, no obstacles, Table 1 rewards.
fn corridor() -> Scenario {
    let mut s = scenario("paper_simple");
    s.name = "corridor".into();
    s.bounds = Bounds {
        min: [0, -2, 4],
        max: [2, -2, 4],
    };
    s.start = [0, -2, 4];
    s.target = [2, -2, 4];
    s.obstacles.clear();
    s.validate().unwrap();
    s
}

fn only_detour() -> Assist {
    Assist {
        detour: true,
        distance: false,
    }
}

fn only_distance() -> Assist {
    Assist {
        detour: false,
        distance: true,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

macro_rules! assert_close {
    ($a:expr, $b:expr) => {{
        let (a, b) = ($a, $b);
        assert!(close(a, b), "{} = {a}, expected {b}", stringify!($a));
    }};
}

fn dist(a: Cell, b: Cell) -> f64 {
    (0..3)
        .map(|i| ((a[i] - b[i]) as f64).powi(2))
        .sum::<f64>()
        .sqrt()
}

// ---------------------------------------------------------------- rewards, eqs. 5, 9, 10

#[test]
fn actions_and_opposites() {
    assert_eq!(ACTIONS[PX], [1, 0, 0]);
    assert_eq!(ACTIONS[MX], [-1, 0, 0]);
    assert_eq!(ACTIONS[PY], [0, 1, 0]);
    assert_eq!(ACTIONS[MY], [0, -1, 0]);
    assert_eq!(ACTIONS[PZ], [0, 0, 1]);
    assert_eq!(ACTIONS[MZ], [0, 0, -1]);
    assert_eq!(opposite(PX), MX);
    assert_eq!(opposite(MZ), PZ);
}

#[test]
fn eq5_plain_step_reach_and_bounds_collision_in_corridor() {
    let w = GridWorld::new(&corridor()).unwrap();
    let s0 = w.state_of([0, -2, 4]).unwrap();
    let s1 = w.state_of([1, -2, 4]).unwrap();
    let s2 = w.state_of([2, -2, 4]).unwrap();
    assert_eq!((w.start(), w.target()), (s0, s2));
    assert_eq!(w.start_distance_cells(), 2.0);

    // Plain step: -p; with eq. 10, + r_e (d_o - d_t) = 40 * (2 - 1).
    let t = w.step(s0, PX, None, Assist::off());
    assert_eq!(
        t,
        Transition {
            next: s1,
            reward: -15000.0,
            collided: false,
            reached: false
        }
    );
    assert_eq!(w.step(s0, PX, None, Assist::on()).reward, -14960.0);
    assert_eq!(w.step(s0, PX, None, only_distance()).reward, -14960.0);
    assert_eq!(w.step(s0, PX, None, only_detour()).reward, -15000.0);

    // Reaching the target: +r; eq. 10 applies on the reaching step too: + 40 * (2 - 0).
    let t = w.step(s1, PX, None, Assist::off());
    assert_eq!((t.next, t.reached, t.collided), (s2, true, false));
    assert_eq!(t.reward, 20000.0);
    assert_eq!(w.step(s1, PX, None, Assist::on()).reward, 20080.0);

    // Out of bounds: -P, the terminal stays; eq. 10 at the unchanged cell: 40 * (2 - 2) = 0.
    for a in [MX, PY, MY, PZ, MZ] {
        let t = w.step(s0, a, None, Assist::off());
        assert_eq!(
            (t.next, t.collided, t.reached),
            (s0, true, false),
            "action {a}"
        );
        assert_eq!(t.reward, -8000.0);
        assert_eq!(w.step(s0, a, None, Assist::on()).reward, -8000.0);
        assert!(w.move_collides(s0, a));
    }
    // From x = 1 a bounds collision keeps d_t = 1: -8000 + 40 * (2 - 1).
    assert_eq!(w.step(s1, PY, None, Assist::on()).reward, -7960.0);
    // A collision never reaches the target, even standing on it.
    let t = w.step(s2, PX, None, Assist::off());
    assert_eq!(
        (t.next, t.collided, t.reached, t.reward),
        (s2, true, false, -8000.0)
    );
    // Moving away from the target costs no more than -p here (d_t back to d_o = 2).
    assert_eq!(w.step(s1, MX, None, Assist::on()).reward, -15000.0);
}

#[test]
fn eq5_obstacle_collision_on_paper_simple() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let d_o = 41f64.sqrt(); // |(0,3,0) - (0,-2,4)|
    assert_close!(w.start_distance_cells(), d_o);
    // (0,0,0) +y -> (0,1,0) is an obstacle: the terminal stays at (0,0,0), d_t = 3.
    let s = w.state_of([0, 0, 0]).unwrap();
    assert!(w.is_blocked(w.state_of([0, 1, 0]).unwrap()));
    assert!(!w.is_blocked(s));
    let t = w.step(s, PY, None, Assist::off());
    assert_eq!(
        (t.next, t.collided, t.reached, t.reward),
        (s, true, false, -8000.0)
    );
    let t = w.step(s, PY, None, Assist::on());
    assert_close!(t.reward, -8000.0 + 40.0 * (d_o - 3.0));
    assert_close!(w.distance_to_target_cells(s), 3.0);
    // The neighbour (0,0,1) is free: distance 1 to obstacle (0,1,1) exceeds d_s = 0.96.
    let t = w.step(s, PZ, None, Assist::off());
    assert!(!t.collided);
    assert_eq!(w.cell_of(t.next), [0, 0, 1]);
}

#[test]
fn collision_rule_uses_the_safe_distance_not_obstacle_cells() {
    // With d_s = 1.0 (not a valid scenario value, but the world applies the rule) the six
    // face neighbours of an obstacle collide too; diagonal ones (sqrt 2) do not.
    let mut sc = corridor();
    sc.bounds = Bounds {
        min: [-3, -3, 1],
        max: [3, 3, 5],
    };
    sc.obstacles = vec![[2, 0, 3]];
    sc.terminal_safe_distance = 1.0;
    let w = GridWorld::new(&sc).unwrap();
    assert_eq!(w.num_blocked(), 7);
    assert!(w.is_blocked(w.state_of([1, 0, 3]).unwrap()));
    assert!(!w.is_blocked(w.state_of([1, 1, 3]).unwrap()));
    let s = w.state_of([0, 0, 3]).unwrap();
    assert!(w.move_collides(s, PX));
    sc.terminal_safe_distance = 0.99;
    let w = GridWorld::new(&sc).unwrap();
    assert_eq!(w.num_blocked(), 1);
    assert!(!w.move_collides(s, PX));
}

#[test]
fn eq9_repeat_collision_and_reverse_after_collision() {
    let w = GridWorld::new(&corridor()).unwrap();
    let s0 = w.start();
    let s1 = w.state_of([1, -2, 4]).unwrap();

    // After a collision with -x: colliding again (any action) costs an extra p_e.
    for a in [MX, PY, MY, PZ, MZ] {
        let t = w.step(s0, a, Some(MX), only_detour());
        assert_eq!(t.reward, -8000.0 - 230000.0, "action {a}");
        assert_eq!(w.step(s0, a, Some(MX), Assist::on()).reward, -238000.0);
        assert_eq!(w.step(s0, a, Some(MX), Assist::off()).reward, -8000.0);
    }
    // ... the opposite action (+x) costs an extra p_o (and here does not collide).
    let t = w.step(s0, PX, Some(MX), only_detour());
    assert_eq!((t.next, t.collided), (s1, false));
    assert_eq!(t.reward, -15000.0 - 10000.0);
    assert_eq!(w.step(s0, PX, Some(MX), Assist::on()).reward, -24960.0);
    assert_eq!(w.step(s0, PX, Some(MX), Assist::off()).reward, -15000.0);
    assert_eq!(w.step(s0, PX, Some(MX), only_distance()).reward, -14960.0);

    // A reversing move that collides again pays the repeat penalty only (exclusive cases).
    let t = w.step(s0, MY, Some(PY), only_detour());
    assert!(t.collided);
    assert_eq!(t.reward, -238000.0);

    // A non-colliding, non-reversing move after a collision: no extra term.
    let t = w.step(s1, PX, Some(PY), only_detour());
    assert!(t.reached);
    assert_eq!(t.reward, 20000.0);
    // No collision before: no extra term either.
    assert_eq!(w.step(s0, MX, None, only_detour()).reward, -8000.0);
}

#[test]
fn eq10_distance_term_sign() {
    let w = world("paper_simple");
    let start = w.start();
    let d_o = 41f64.sqrt();
    // +z moves away from the target (0,3,0): d_t = sqrt(50) > d_o, a penalty.
    let t = w.step(start, PZ, None, only_distance());
    let away = 40.0 * (d_o - 50f64.sqrt());
    assert!(away < 0.0);
    assert_close!(t.reward, -15000.0 + away);
    // -z moves closer: d_t = sqrt(34) < d_o, a reward.
    let t = w.step(start, MZ, None, only_distance());
    let closer = 40.0 * (d_o - 34f64.sqrt());
    assert!(closer > 0.0);
    assert_close!(t.reward, -15000.0 + closer);
    assert_eq!(w.step(start, MZ, None, Assist::off()).reward, -15000.0);
    // On the target the term is r_e * d_o.
    let pre = w.state_of([1, 3, 0]).unwrap();
    let t = w.step(pre, MX, None, Assist::on());
    assert!(t.reached);
    assert_close!(t.reward, 20000.0 + 40.0 * d_o);
}

// ---------------------------------------------------------------- Q-update, eq. 6

#[test]
fn q_update_by_hand_in_corridor() {
    let w = GridWorld::new(&corridor()).unwrap();
    let (alpha, gamma) = (0.05, 0.9);
    let s0 = w.start();
    let s1 = w.state_of([1, -2, 4]).unwrap();
    let mut q = QTable::zeros(w.num_states());
    let assist = Assist::on();

    // Episode 1: +x, +x.
    let t = w.step(s0, PX, None, assist); // -14960, Q(s1,.) = 0
    assert_close!(q_update(&mut q, s0, PX, &t, alpha, gamma), -748.0);
    let t = w.step(s1, PX, None, assist); // reaches: 20080, terminal, no bootstrap
    assert!(t.reached);
    assert_close!(q_update(&mut q, s1, PX, &t, alpha, gamma), 1004.0);

    // Episode 2: +x bootstraps from max Q(s1,.) = 1004:
    // -748 + 0.05 * (-14960 + 0.9 * 1004 + 748) = -1413.42
    let t = w.step(s0, PX, None, assist);
    assert_close!(q_update(&mut q, s0, PX, &t, alpha, gamma), -1413.42);
    // Back: -x from s1 to s0 (-15000 + 40 * 0), max Q(s0,.) = 0 (untried actions):
    // 0 + 0.05 * (-15000 + 0) = -750
    let t = w.step(s1, MX, None, assist);
    assert_close!(q_update(&mut q, s1, MX, &t, alpha, gamma), -750.0);
    // Collision with the wall, -x at s0: -8000, bootstrap max Q(s0,.) = 0 -> -400.
    let t = w.step(s0, MX, None, assist);
    assert!(t.collided);
    assert_close!(q_update(&mut q, s0, MX, &t, alpha, gamma), -400.0);
    // Reverse after that collision, +x: -15000 + 40 - 10000 = -24960, max Q(s1,.) = 1004:
    // -1413.42 + 0.05 * (-24960 + 903.6 + 1413.42) = -2545.569
    let t = w.step(s0, PX, Some(MX), assist);
    assert_eq!(t.reward, -24960.0);
    assert_close!(q_update(&mut q, s0, PX, &t, alpha, gamma), -2545.569);

    assert_close!(q.get(s0, PX), -2545.569);
    assert_close!(q.get(s0, MX), -400.0);
    assert_close!(q.get(s1, PX), 1004.0);
    assert_close!(q.get(s1, MX), -750.0);
    assert_eq!(q.values().iter().filter(|v| **v != 0.0).count(), 4);
    // Greedy actions: ties broken by the lowest index.
    assert_eq!(q.greedy_action(s1), PX);
    assert_eq!(q.greedy_action(s0), PY); // +x, -x negative; +y is the first 0
}

/// The learner of the module docs, written plainly with `GridWorld::step` and `q_update`.
fn reference_train(world: &GridWorld, o: &Learning, q0: Option<QTable>) -> (QTable, Vec<u32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(o.seed);
    let mut q = q0.unwrap_or_else(|| QTable::zeros(world.num_states()));
    let mut steps_per_episode = Vec::new();
    for ep in 0..o.episodes {
        let threshold = (o.epsilon(ep) * 4_294_967_296.0).ceil() as u64;
        let mut s = world.start();
        let mut last = None;
        let mut steps = 0;
        while steps < o.max_steps_per_episode {
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
            let t = world.step(s, a, last, o.assist());
            q_update(&mut q, s, a, &t, o.alpha, o.gamma);
            last = t.collided.then_some(a);
            s = t.next;
            steps += 1;
            if t.reached {
                break;
            }
        }
        steps_per_episode.push(steps);
    }
    (q, steps_per_episode)
}

#[test]
fn learner_matches_plain_reference_bit_for_bit() {
    for (name, seed, assist, episodes) in [
        ("paper_simple", 7, Assist::on(), 600),
        ("paper_simple", 8, Assist::off(), 600),
        ("paper_simple", 9, only_detour(), 300),
        ("replan_clutter", 10, only_distance(), 300),
    ] {
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let mut o = Learning::from_scenario(&sc);
        o.seed = seed;
        o.set_assist(assist);
        o.episodes = episodes;
        o.epsilon_decay_episodes = episodes - 50;
        o.max_steps_per_episode = 300;
        let r = train(&w, &o, None, None).unwrap();
        let (q, steps) = reference_train(&w, &o, None);
        assert_eq!(r.q, q, "{name} seed {seed}");
        assert_eq!(r.steps_per_episode, steps);
        assert_eq!(r.total_steps, steps.iter().map(|&s| s as u64).sum::<u64>());
        assert_eq!(r.path, greedy_path(&w, &r.q, o.max_steps_per_episode));
    }
}

#[test]
fn truncated_episodes_bootstrap_and_terminal_ones_do_not() {
    // One-step episodes in the corridor, greedy (epsilon 0): the first step from s0 draws
    // among six tied zero actions; whatever it is, the update must bootstrap (no target).
    let sc = corridor();
    let w = GridWorld::new(&sc).unwrap();
    let mut o = Learning::from_scenario(&sc);
    o.episodes = 1;
    o.max_steps_per_episode = 1;
    o.epsilon_start = 0.0;
    let mut q0 = QTable::zeros(w.num_states());
    let s1 = w.state_of([1, -2, 4]).unwrap();
    for a in 0..6 {
        q0.set(s1, a, 100.0);
    }
    // Make +x at s0 the unique greedy action.
    q0.set(w.start(), PX, 1.0);
    for a in 1..6 {
        q0.set(w.start(), a, -1.0);
    }
    let r = train(&w, &o, Some(q0.clone()), None).unwrap();
    assert_eq!(r.steps_per_episode, vec![1]);
    assert_eq!(r.reached_per_episode, vec![false]);
    // 1 + 0.05 * (-14960 + 0.9 * 100 - 1)
    assert_close!(r.q.get(w.start(), PX), 1.0 + 0.05 * (-14960.0 + 90.0 - 1.0));

    // From s1 the target is one step away: no bootstrap from the target's row.
    let mut w1 = w.clone();
    w1.set_start([1, -2, 4]).unwrap();
    let mut q1 = QTable::zeros(w.num_states());
    for a in 0..6 {
        q1.set(w.target(), a, 1e6); // would show up if bootstrapped
    }
    q1.set(s1, PX, 1.0);
    let r = train(&w1, &o, Some(q1), None).unwrap();
    assert_eq!(r.reached_per_episode, vec![true]);
    // d_o is now 1, d_t = 0: reward 20000 + 40.
    assert_close!(r.q.get(s1, PX), 1.0 + 0.05 * (20040.0 - 1.0));
}

// ---------------------------------------------------------------- learner

#[test]
fn same_seed_same_run_different_seed_different_steps() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut o = Learning::from_scenario(&sc);
    o.episodes = 2000;
    o.epsilon_decay_episodes = 1980;
    let a = train(&w, &o, None, None).unwrap();
    let b = train(&w, &o, None, None).unwrap();
    assert_eq!(a.q.values(), b.q.values());
    assert_eq!(a.path, b.path);
    assert_eq!(a.steps_per_episode, b.steps_per_episode);
    assert_eq!(a.reached_per_episode, b.reached_per_episode);
    assert_eq!(a.converged_episode, b.converged_episode);
    o.seed = 1;
    let c = train(&w, &o, None, None).unwrap();
    assert_ne!(a.steps_per_episode, c.steps_per_episode);
    assert_ne!(a.q.values(), c.q.values());
}

fn check_path(w: &GridWorld, path: &[Cell]) {
    assert_eq!(path.first(), Some(&w.cell_of(w.start())));
    assert_eq!(path.last(), Some(&w.cell_of(w.target())));
    for pair in path.windows(2) {
        let d: i32 = (0..3).map(|i| (pair[1][i] - pair[0][i]).abs()).sum();
        assert_eq!(d, 1, "not contiguous: {pair:?}");
    }
    for (i, c) in path.iter().enumerate() {
        let s = w.state_of(*c).expect("inside bounds");
        assert!(!w.is_blocked(s), "{c:?} is blocked");
        for o in w.obstacles() {
            assert!(dist(*c, *o) > w.terminal_safe_distance());
        }
        assert!(!path[..i].contains(c), "{c:?} revisited");
    }
}

#[test]
fn paper_simple_learns_a_path_with_default_10k_episodes() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let o = Learning::from_scenario(&sc);
    assert_eq!(o.episodes, 10_000);
    assert_eq!(o.assist(), Assist::on());
    let r = train(&w, &o, None, None).unwrap();
    let path = r
        .path
        .as_ref()
        .expect("the learned path reaches the target");
    check_path(&w, path);
    let bfs = w.shortest_path().unwrap();
    println!(
        "paper_simple seed 0: learned path {} steps, BFS {} steps, converged at episode {:?}, {} env steps, {:.1} ms",
        path.len() - 1,
        bfs.len() - 1,
        r.converged_episode,
        r.total_steps,
        r.wall_time_s * 1e3
    );
    assert!(path.len() >= bfs.len());
    assert_eq!(r.steps_per_episode.len(), 10_000);
    assert_eq!(r.reached_per_episode.len(), 10_000);
    let conv = r.converged_episode.expect("a final path");
    assert!(conv < 10_000);
    assert!(r.length_converged_episode.unwrap() <= conv);
    // The last, purely greedy episodes walk the learned path.
    assert!(r.reached_per_episode[9901..].iter().all(|&x| x));
    assert!(r.steps_per_episode[9901..]
        .iter()
        .all(|&n| n as usize == path.len() - 1));
}

#[test]
fn converged_episode_matches_its_definition() {
    // Training k episodes replays the first k episodes of a longer run (the epsilon
    // schedule depends on M, not on the number of episodes), so the greedy path after
    // episode e is that of a run with e + 1 episodes.
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut o = Learning::from_scenario(&sc);
    o.seed = 4;
    let full = train(&w, &o, None, None).unwrap();
    let conv = full.converged_episode.expect("converges") as u32;
    let path_after = |e: u32| {
        let mut o2 = o;
        o2.episodes = e + 1;
        let r = train(&w, &o2, None, None).unwrap();
        assert_eq!(
            r.steps_per_episode[..],
            full.steps_per_episode[..=e as usize]
        );
        r.path
    };
    println!("paper_simple, seed 4: converged at episode {conv}");
    assert!(conv < o.episodes - 1);
    assert_eq!(path_after(conv), full.path);
    assert_eq!(path_after((conv + o.episodes - 1) / 2), full.path);
    if conv > 0 {
        assert_ne!(path_after(conv - 1), full.path);
    }
}

#[test]
fn report_seeds_0_to_4_on_paper_scenarios() {
    for name in ["paper_simple", "paper_complex"] {
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let bfs = w.shortest_path().unwrap().len() - 1;
        for assist in [Assist::on(), Assist::off()] {
            let mut line = format!(
                "{name} (BFS {bfs}) {}: ",
                if assist.detour { "assist" } else { "no assist" }
            );
            for seed in 0..5 {
                let mut o = Learning::from_scenario(&sc);
                o.seed = seed;
                o.set_assist(assist);
                let r = train(&w, &o, None, None).unwrap();
                if let Some(p) = &r.path {
                    check_path(&w, p);
                }
                if assist == Assist::on() {
                    assert!(r.path.is_some(), "{name} seed {seed}");
                }
                line += &format!(
                    "seed {seed}: len {:?} conv {:?} (length {:?}); ",
                    r.path.as_ref().map(|p| p.len() - 1),
                    r.converged_episode,
                    r.length_converged_episode
                );
            }
            println!("{line}");
        }
    }
}

#[test]
fn progress_is_called_at_most_about_100_times() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut o = Learning::from_scenario(&sc);
    for episodes in [1u32, 7, 100, 1234] {
        o.episodes = episodes;
        let calls = std::cell::RefCell::new(Vec::new());
        let cb = |n: u32| calls.borrow_mut().push(n);
        train(&w, &o, None, Some(&cb)).unwrap();
        let calls = calls.into_inner();
        assert!(!calls.is_empty() && calls.len() <= 101, "{}", calls.len());
        assert_eq!(*calls.last().unwrap(), episodes);
        assert!(calls.windows(2).all(|p| p[0] < p[1]));
    }
}

#[test]
fn bad_options_and_wrong_table_are_errors() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let o = Learning::from_scenario(&sc);
    for bad in [
        Learning { episodes: 0, ..o },
        Learning { alpha: 0.0, ..o },
        Learning { gamma: 1.5, ..o },
        Learning {
            epsilon_start: -0.1,
            ..o
        },
        Learning {
            max_steps_per_episode: 0,
            ..o
        },
    ] {
        assert!(matches!(
            train(&w, &bad, None, None),
            Err(Error::InvalidArgument { .. })
        ));
    }
    assert!(matches!(
        train(&w, &o, Some(QTable::zeros(3)), None),
        Err(Error::QTableMismatch(_))
    ));
}

#[test]
fn serde_of_options_and_result() {
    let o = Learning::from_scenario(&scenario("paper_simple"));
    let text = serde_json::to_string(&o).unwrap();
    assert!(
        text.contains("\"assist_detour\":true,\"assist_distance\":true"),
        "{text}"
    );
    let back: Learning = serde_json::from_str(&text).unwrap();
    assert_eq!(back, o);
    let a: Assist = serde_json::from_str(r#"{"detour":false,"distance":true}"#).unwrap();
    assert_eq!(a, only_distance());
    assert_eq!(Assist::default(), Assist::off());

    let w = GridWorld::new(&corridor()).unwrap();
    let mut o = Learning::from_scenario(&corridor());
    o.episodes = 3;
    let r = train(&w, &o, None, None).unwrap();
    let v: serde_json::Value = serde_json::to_value(&r).unwrap();
    assert_eq!(v["path"][0], serde_json::json!([0, -2, 4]));
    assert!(v.get("q").is_none());
    assert_eq!(v["steps_per_episode"].as_array().unwrap().len(), 3);
}

// ---------------------------------------------------------------- BFS

#[test]
fn bfs_shortest_path_on_paper_simple() {
    let w = world("paper_simple");
    let p = w.shortest_path().unwrap();
    check_path(&w, &p);
    // The Manhattan distance from (0,-2,4) to (0,3,0) is 9, a lower bound, and reached.
    assert_eq!(p.len() - 1, 9);
    println!(
        "paper_simple BFS shortest path: {} steps: {p:?}",
        p.len() - 1
    );
    assert_eq!(w.shortest_path(), Some(p), "deterministic");
    let shelf = world("replan_clutter");
    let p = shelf.shortest_path().unwrap();
    check_path(&shelf, &p);
    println!("replan_clutter BFS shortest path: {} steps", p.len() - 1);
}

#[test]
fn walled_in_target_has_no_path() {
    let sc = scenario("paper_simple");
    let t = sc.target;
    let walls: Vec<Cell> = ACTIONS
        .iter()
        .map(|m| [t[0] + m[0], t[1] + m[1], t[2] + m[2]])
        .collect();
    let w = GridWorld::with_extra_obstacles(&sc, &walls).unwrap();
    assert_eq!(w.shortest_path(), None);
    let mut o = Learning::from_scenario(&sc);
    o.episodes = 50;
    o.max_steps_per_episode = 200;
    let r = train(&w, &o, None, None).unwrap();
    assert_eq!(r.path, None);
    assert_eq!(r.converged_episode, None);
    assert!(r.reached_per_episode.iter().all(|&x| !x));
    assert!(r.steps_per_episode.iter().all(|&n| n == 200));
}

// ---------------------------------------------------------------- Q-table files

fn trained(w: &GridWorld, sc: &Scenario, episodes: u32, seed: u64) -> QTable {
    let mut o = Learning::from_scenario(sc);
    o.episodes = episodes;
    o.seed = seed;
    train(w, &o, None, None).unwrap().q
}

#[test]
fn qtable_save_load_roundtrip_is_exact() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 500, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!(back, q);
    assert!(back
        .values()
        .iter()
        .zip(q.values())
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    // Overwriting works and leaves only the file.
    let q2 = trained(&w, &sc, 50, 1);
    q2.save(&path, &w).unwrap();
    assert_eq!(QTable::load(&path, &w).unwrap(), q2);
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
    let text = std::fs::read(&path).unwrap();
    assert!(text.starts_with(b"SIXAXIS-QTABLE 1\n{"));
}

#[test]
fn qtable_load_onto_another_world_is_a_mismatch() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 100, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();

    // paper_complex: same cells blocked (d_s 0.95 vs 0.96 < 1), same bounds and target.
    let complex = GridWorld::new(&scenario("paper_complex")).unwrap();
    assert_eq!(QTable::load(&path, &complex).unwrap(), q);

    let mismatch = |w: &GridWorld| match QTable::load(&path, w) {
        Err(Error::QTableMismatch(msg)) => msg,
        other => panic!("expected a mismatch, got {other:?}"),
    };
    let shelf = GridWorld::new(&scenario("replan_clutter")).unwrap();
    let msg = mismatch(&shelf);
    assert!(msg.contains("obstacles differ"), "{msg}");
    let extra = GridWorld::with_extra_obstacles(&sc, &[[0, 0, 0]]).unwrap();
    mismatch(&extra);
    let mut moved = w.clone();
    moved.set_target([2, 2, 2]).unwrap();
    assert!(mismatch(&moved).contains("target"));
    let mut small = sc.clone();
    small.bounds.max = [3, 5, 4];
    let msg = mismatch(&GridWorld::new(&small).unwrap());
    assert!(msg.contains("bounds"), "{msg}");
    // A table of the wrong size cannot be saved for this world either.
    assert!(matches!(
        QTable::zeros(5).save(&dir.path().join("x"), &w),
        Err(Error::QTableMismatch(_))
    ));
    // The start is recorded but does not have to match.
    let mut moved_start = w.clone();
    moved_start.set_start([0, -2, 3]).unwrap();
    assert_eq!(QTable::load(&path, &moved_start).unwrap(), q);
}

/// Whether loading gave an I/O error of kind `InvalidData` (a bad file, not a missing one).
fn is_invalid_data(r: sixaxis_core::Result<QTable>) -> bool {
    matches!(r, Err(Error::Io { ref source, .. }) if source.kind() == std::io::ErrorKind::InvalidData)
}

#[test]
fn corrupt_or_foreign_files_are_io_errors() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 50, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let good = std::fs::read(&path).unwrap();
    // Truncated.
    std::fs::write(&path, &good[..good.len() - 8]).unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // A flipped bit in the values.
    let mut bad = good.clone();
    let last = bad.len() - 1;
    bad[last] ^= 1;
    std::fs::write(&path, &bad).unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // Not a Q-table.
    std::fs::write(&path, b"{\"hello\": 1}").unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // Missing.
    assert!(matches!(
        QTable::load(&dir.path().join("missing"), &w),
        Err(Error::Io { .. })
    ));
}

#[test]
fn qtable_save_is_atomic_and_leaves_nothing_on_error() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 50, 0);
    let dir = tempfile::tempdir().unwrap();
    // The destination is a directory: the final rename fails after the temporary file
    // was written; the temporary file must be gone.
    let target = dir.path().join("occupied");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"x").unwrap();
    let err = q.save(&target, &w).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["occupied".to_string()]);
    // A missing directory: an error, nothing created.
    let err = q
        .save(&dir.path().join("no/such/dir/q.qtable"), &w)
        .unwrap_err();
    assert!(matches!(err, Error::Io { .. }));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // An existing file is replaced whole, never left half-written: after a failed save
    // onto a good file the good file is intact.
    let good = dir.path().join("good.qtable");
    q.save(&good, &w).unwrap();
    assert!(QTable::zeros(3).save(&good, &w).is_err());
    assert_eq!(QTable::load(&good, &w).unwrap(), q);
}

// ---------------------------------------------------------------- resume

#[test]
fn resume_from_saved_table_is_deterministic() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut first = Learning::from_scenario(&sc);
    first.episodes = 1500;
    first.epsilon_decay_episodes = 3000;
    first.seed = 11;
    let r1 = train(&w, &first, None, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    r1.q.save(&path, &w).unwrap();

    // The second run: its own seed and its own epsilon schedule, counted from 0.
    let mut second = first;
    second.seed = 12;
    second.episodes = 1000;
    second.epsilon_start = 0.05;
    second.epsilon_decay_episodes = 900;
    let a = train(&w, &second, Some(QTable::load(&path, &w).unwrap()), None).unwrap();
    let b = train(&w, &second, Some(QTable::load(&path, &w).unwrap()), None).unwrap();
    let c = train(&w, &second, Some(r1.q.clone()), None).unwrap();
    assert_eq!(a.q, b.q);
    assert_eq!(a.q, c.q);
    assert_eq!(a.steps_per_episode, b.steps_per_episode);
    assert_eq!(a.path, b.path);
    assert_eq!(a.converged_episode, b.converged_episode);
    // Equal to the plain reference learner started from the same table.
    let (q_ref, steps_ref) = reference_train(&w, &second, Some(r1.q.clone()));
    assert_eq!(a.q, q_ref);
    assert_eq!(a.steps_per_episode, steps_ref);
    // Another seed for the second run gives another run.
    second.seed = 13;
    let d = train(&w, &second, Some(r1.q.clone()), None).unwrap();
    assert_ne!(a.steps_per_episode, d.steps_per_episode);
    // Resuming changed the table (it learned).
    assert_ne!(a.q, r1.q);
    if let Some(p) = &a.path {
        check_path(&w, p);
    }
}

#[test]
fn resume_continues_learning_to_a_path() {
    // 5000 episodes, then 5000 more from that table with the rest of the paper's schedule
    // (epsilon from 0.05 down to 0 over 4900 episodes): the path is learned.
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut first = Learning::from_scenario(&sc);
    first.episodes = 5000;
    let r1 = train(&w, &first, None, None).unwrap();
    let mut second = first;
    second.seed = 1;
    second.epsilon_start = first.epsilon(5000);
    second.epsilon_decay_episodes = 4900;
    let r2 = train(&w, &second, Some(r1.q), None).unwrap();
    let p = r2.path.expect("resumed run reaches the target");
    check_path(&w, &p);
    println!(
        "paper_simple 5000 + 5000 episodes: path {} steps, converged at episode {:?} of the second run",
        p.len() - 1,
        r2.converged_episode
    );
}

// ---------------------------------------------------------------- f32 Q-values

fn f32_options(sc: &Scenario, episodes: u32, seed: u64) -> Learning {
    let mut o = Learning::from_scenario(sc);
    o.episodes = episodes;
    o.epsilon_decay_episodes = episodes - episodes / 100;
    o.seed = seed;
    o.q_precision = QPrecision::F32;
    o
}

#[test]
fn f32_learner_matches_plain_reference_bit_for_bit() {
    // The same learner with its values stored as f32: the plain reference learner
    // (`q_update`, which computes in f64 and stores rounded) on an f32 table gives the same
    // table, bit for bit, and the same episodes.
    for (name, seed, assist, episodes) in [
        ("paper_simple", 7, Assist::on(), 600),
        ("paper_simple", 8, Assist::off(), 600),
        ("replan_clutter", 10, only_distance(), 300),
    ] {
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let mut o = f32_options(&sc, episodes, seed);
        o.set_assist(assist);
        o.max_steps_per_episode = 300;
        let r = train(&w, &o, None, None).unwrap();
        assert_eq!(r.q.precision(), QPrecision::F32);
        let q0 = QTable::zeros_with(w.num_states(), QPrecision::F32);
        let (q, steps) = reference_train(&w, &o, Some(q0));
        assert_eq!(r.q, q, "{name} seed {seed}");
        assert_eq!(r.steps_per_episode, steps);
        assert_eq!(r.path, greedy_path(&w, &r.q, o.max_steps_per_episode));
    }
}

#[test]
fn f32_training_is_deterministic_and_takes_half_the_bytes() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let o = f32_options(&sc, 2000, 0);
    let a = train(&w, &o, None, None).unwrap();
    let b = train(&w, &o, None, None).unwrap();
    assert_eq!(a.q, b.q);
    assert_eq!(a.path, b.path);
    assert_eq!(a.steps_per_episode, b.steps_per_episode);
    assert_eq!(a.converged_episode, b.converged_episode);
    // Every value is an f32 (read back as f64 exactly).
    let v32 = a.q.values_f32().unwrap();
    assert!(a.q.values_f64().is_none());
    assert!(a
        .q
        .values()
        .iter()
        .zip(v32)
        .all(|(x, y)| x.to_bits() == (*y as f64).to_bits()));
    assert!(v32.iter().filter(|v| **v != 0.0).count() > 100);
    let c = train(&w, &Learning { seed: 1, ..o }, None, None).unwrap();
    assert_ne!(a.q, c.q);
    // 24 bytes of Q-values per state against 48; the default stays f64.
    let f64_run = train(
        &w,
        &Learning {
            q_precision: QPrecision::F64,
            ..o
        },
        None,
        None,
    )
    .unwrap();
    assert_eq!(
        (a.q.bytes_per_state(), f64_run.q.bytes_per_state()),
        (24, 48)
    );
    assert_eq!(Learning::from_scenario(&sc).q_precision, QPrecision::F64);
    // The f64 learner asked for explicitly is the default learner, bit for bit.
    let mut default = Learning::from_scenario(&sc);
    default.episodes = 2000;
    default.epsilon_decay_episodes = 1980;
    assert_eq!(train(&w, &default, None, None).unwrap().q, f64_run.q);
}

#[test]
fn f32_qtable_file_round_trip_is_exact() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = train(&w, &f32_options(&sc, 500, 3), None, None).unwrap().q;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q32.qtable");
    q.save(&path, &w).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header_end = bytes.iter().skip(17).position(|&b| b == b'\n').unwrap() + 18;
    let header = std::str::from_utf8(&bytes[17..header_end]).unwrap();
    assert!(header.contains("\"values\":\"f32\""), "{header}");
    assert!(
        header.contains("\"layout\":\"f32 little-endian"),
        "{header}"
    );
    assert_eq!(bytes.len() - header_end, w.num_states() * 6 * 4);
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!(back.precision(), QPrecision::F32);
    assert_eq!(back, q);
    let bits = |t: &QTable| -> Vec<u32> {
        t.values_f32()
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&back), bits(&q));
    // An f64 table says so too, and is twice the size.
    let q64 = trained(&w, &sc, 50, 0);
    let p64 = dir.path().join("q64.qtable");
    q64.save(&p64, &w).unwrap();
    let b64 = std::fs::read(&p64).unwrap();
    assert!(String::from_utf8_lossy(&b64).contains("\"values\":\"f64\""));
    assert_eq!(QTable::load(&p64, &w).unwrap().precision(), QPrecision::F64);
}

#[test]
fn qtable_file_without_a_value_type_reads_as_f64() {
    // Files written before f32 tables existed have no `values` field in the header.
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 200, 2);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let text = std::fs::read(&path).unwrap();
    let field = b"\"values\":\"f64\",";
    let at = text.windows(field.len()).position(|x| x == field).unwrap();
    let mut old = text[..at].to_vec();
    old.extend_from_slice(&text[at + field.len()..]);
    std::fs::write(&path, &old).unwrap();
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!((back.precision(), &back), (QPrecision::F64, &q));
    // A header claiming f32 over f64 values, or naming another type, is refused.
    for claim in [&b"\"values\":\"f32\","[..], b"\"values\":\"f16\","] {
        let mut lie = text[..at].to_vec();
        lie.extend_from_slice(claim);
        lie.extend_from_slice(&text[at + field.len()..]);
        std::fs::write(&path, &lie).unwrap();
        assert!(is_invalid_data(QTable::load(&path, &w)));
    }
}

#[test]
fn a_table_of_the_other_precision_is_converted_for_training() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut o = f32_options(&sc, 300, 4);
    let q64 = trained(&w, &sc, 400, 1);
    // f64 table, f32 run: rounded to the nearest f32 first.
    let a = train(&w, &o, Some(q64.clone()), None).unwrap();
    let rounded = q64.clone().into_precision(QPrecision::F32).unwrap();
    assert!(rounded
        .values()
        .iter()
        .zip(q64.values())
        .all(|(r, v)| *r == (v as f32) as f64));
    let b = train(&w, &o, Some(rounded.clone()), None).unwrap();
    assert_eq!(a.q.precision(), QPrecision::F32);
    assert_eq!(a.q, b.q);
    // f32 table, f64 run: exact.
    o.q_precision = QPrecision::F64;
    let widened = rounded.clone().into_precision(QPrecision::F64).unwrap();
    assert_eq!(widened.values(), rounded.values());
    let c = train(&w, &o, Some(rounded), None).unwrap();
    let d = train(&w, &o, Some(widened), None).unwrap();
    assert_eq!(c.q.precision(), QPrecision::F64);
    assert_eq!(c.q, d.q);
    // A value beyond the f32 range cannot be converted: an error naming it.
    let mut big = QTable::zeros(w.num_states());
    big.set(5, 2, 1e39);
    o.q_precision = QPrecision::F32;
    let e = train(&w, &o, Some(big), None).unwrap_err().to_string();
    assert!(
        e.contains("`q_precision` = f32") && e.contains("(state 5, action 2) does not fit in f32"),
        "{e}"
    );
}

#[test]
fn f32_q_update_stores_the_rounded_f64_update() {
    let sc = corridor();
    let w = GridWorld::new(&sc).unwrap();
    let s0 = w.start();
    let mut q = QTable::zeros_with(w.num_states(), QPrecision::F32);
    q.set(s0, PX, 0.1);
    assert_eq!(q.get(s0, PX), 0.1f32 as f64);
    let t = w.step(s0, PX, None, Assist::on());
    let expect = (0.1f32 as f64) + 0.05 * (t.reward + 0.9 * 0.0 - (0.1f32 as f64));
    assert_eq!(
        q_update(&mut q, s0, PX, &t, 0.05, 0.9),
        expect as f32 as f64
    );
    assert_eq!(q.row(s0)[PX], expect as f32 as f64);
}
