//! Rewards: eqs. 5, 9, 10.

use super::*;

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
