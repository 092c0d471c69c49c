//! Breadth-first shortest paths.

use super::*;

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
