//! The Q-update (eq. 6) against a plain reference learner.

use super::*;

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
