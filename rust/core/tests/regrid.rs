//! Physical worlds and re-gridding: the same boxes block the same places at every cell size,
//! and the learner finds the BFS optimum at each size.

use serde_json::json;
use sixaxis_core::grid::GridWorld;
use sixaxis_core::planner::PosePlanner;
use sixaxis_core::qlearning::{train, Learning};
use sixaxis_core::regrid::regrid;
use sixaxis_core::replanning::{plan, PlanOptions};
use sixaxis_core::scenario::{DistanceTo, InitialQ, ObstacleBox, QPrecision};
use sixaxis_core::{Error, Scenario};

/// Cells (as mm points) blocked by brute force: a cell is blocked when its centre is within
/// d_s (mm) of some obstacle by its rule.
fn brute_blocked(s: &Scenario, w: &GridWorld) -> Vec<bool> {
    let ds = s.terminal_safe_distance_in_mm();
    let mut boxes: Vec<ObstacleBox> = s
        .obstacles
        .iter()
        .map(|&c| ObstacleBox::paper_cube(c, s.cell_mm))
        .collect();
    boxes.extend_from_slice(&s.obstacle_boxes_mm);
    (0..w.num_states())
        .map(|st| {
            let p = w.cell_of(st).map(|v| v as f64 * s.cell_mm);
            boxes.iter().any(|b| b.terminal_distance_mm(p) <= ds + 1e-9)
        })
        .collect()
}

#[test]
fn regridded_paper_world_blocks_the_same_places() {
    let s = Scenario::builtin("paper_simple").unwrap();
    for cell in [100.0, 50.0, 25.0, 12.5] {
        let r = regrid(&s, cell).unwrap();
        assert_eq!(r.terminal_safe_distance_mm, Some(96.0));
        assert_eq!(r.arm_safe_distance_mm, Some(76.0));
        assert_eq!(r.start.map(|v| v as f64 * cell), [0.0, -200.0, 400.0]);
        assert_eq!(r.target.map(|v| v as f64 * cell), [0.0, 300.0, 0.0]);
        assert_eq!(
            r.bounds.min.map(|v| v as f64 * cell),
            [-300.0, -300.0, -200.0]
        );
        assert_eq!(r.bounds.max.map(|v| v as f64 * cell), [300.0, 500.0, 500.0]);
        let w = GridWorld::new(&r).unwrap();
        let want = brute_blocked(&r, &w);
        let got: Vec<bool> = (0..w.num_states()).map(|st| w.is_blocked(st)).collect();
        assert_eq!(got, want, "{cell} mm");
        // Every cell of the original grid that is a point of the new one is blocked alike.
        let orig = GridWorld::new(&s).unwrap();
        let k = (100.0 / cell) as i32;
        for st in 0..orig.num_states() {
            let c = orig.cell_of(st).map(|v| v * k);
            assert_eq!(
                w.is_blocked(w.state_of(c).unwrap()),
                orig.is_blocked(st),
                "{c:?} at {cell} mm"
            );
        }
        // The BFS optimum scales with the cell: 9 moves of 100 mm.
        let bfs = w.shortest_path().unwrap().len() - 1;
        assert_eq!(bfs as f64, 9.0 * 100.0 / cell);
    }
}

#[test]
fn surface_boxes_block_exactly_the_cells_inside() {
    // With d_s = 0 a `surface` box blocks exactly the cells whose centre lies in it.
    let mut v = serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap();
    v["obstacles"] = json!([]);
    v["terminal_safe_distance"] = json!(0.0);
    v["obstacle_boxes_mm"] = json!([
        {"min_mm": [-130.0, 20.0, -40.0], "max_mm": [160.0, 110.0, 75.0]},
        {"min_mm": [-300.0, 150.0, 100.0], "max_mm": [-200.0, 260.0, 110.0]}
    ]);
    let s = Scenario::from_json(&v.to_string()).unwrap();
    for cell in [100.0, 50.0, 25.0, 20.0] {
        let r = regrid(&s, cell).unwrap();
        let w = GridWorld::new(&r).unwrap();
        for st in 0..w.num_states() {
            let p = w.cell_of(st).map(|c| c as f64 * cell);
            let inside = r
                .obstacle_boxes_mm
                .iter()
                .any(|b| (0..3).all(|i| p[i] >= b.min_mm[i] && p[i] <= b.max_mm[i]));
            assert_eq!(w.is_blocked(st), inside, "{p:?} at {cell} mm");
        }
        assert!(w.num_blocked() > 0);
    }
}

#[test]
fn regrid_to_the_same_cell_is_bit_identical() {
    for name in ["paper_simple", "paper_complex"] {
        let s = Scenario::builtin(name).unwrap();
        let r = regrid(&s, s.cell_mm).unwrap();
        assert!(r.obstacles.is_empty());
        assert_eq!(r.obstacle_boxes_mm.len(), s.obstacles.len());
        assert!(r
            .obstacle_boxes_mm
            .iter()
            .all(|b| b.distance_to == DistanceTo::Centre));
        let (a, b) = (
            plan(&s, &PlanOptions::from_scenario(&s), None, None).unwrap(),
            { plan(&r, &PlanOptions::from_scenario(&r), None, None).unwrap() },
        );
        assert_eq!(a.path, b.path, "{name}");
        assert_eq!(a.poses_rad, b.poses_rad, "{name}");
        assert_eq!(a.success, b.success);
        // And it survives a JSON round trip.
        assert_eq!(Scenario::from_json(&r.to_json()).unwrap(), r);
    }
}

#[test]
fn auto_episodes_find_the_bfs_optimum_at_each_size() {
    let s = Scenario::builtin("paper_simple").unwrap();
    for cell in [100.0, 50.0, 25.0] {
        let r = regrid(&s, cell).unwrap();
        let w = GridWorld::new(&r).unwrap();
        let opts = Learning::from_scenario(&r).auto();
        let t = train(&w, &opts, None, None).unwrap();
        let path = t.path.expect("a path");
        assert_eq!(path.len(), w.shortest_path().unwrap().len(), "{cell} mm");
        assert!(
            (t.steps_per_episode.len() as u32) < opts.episodes,
            "stopped by the rule"
        );
        for pair in path.windows(2) {
            let d: i32 = (0..3).map(|i| (pair[0][i] - pair[1][i]).abs()).sum();
            assert_eq!(d, 1);
            assert!(!w.is_blocked(w.state_of(pair[1]).unwrap()));
        }
    }
}

/// `learning.initial_q = "distance"` with `--episodes auto` and Q-values in `precision`:
/// the BFS optimum at 100, 50, 25 and 12.5 mm, seeds 0 and 1, before the episode cap.
fn distance_initial_q_finds_the_bfs_optimum(precision: QPrecision) {
    let s = Scenario::builtin("paper_simple").unwrap();
    for cell in [100.0, 50.0, 25.0, 12.5] {
        let r = regrid(&s, cell).unwrap();
        let w = GridWorld::new(&r).unwrap();
        let mut opts = Learning::from_scenario(&r).auto();
        opts.initial_q = InitialQ::Distance;
        opts.q_precision = precision;
        for seed in [0, 1] {
            opts.seed = seed;
            let t = train(&w, &opts, None, None).unwrap();
            assert_eq!(t.q.precision(), precision);
            let path = t.path.expect("a path");
            assert_eq!(
                path.len(),
                w.shortest_path().unwrap().len(),
                "{cell} mm seed {seed} {precision:?}"
            );
            assert_eq!(path[0], r.start);
            assert_eq!(*path.last().unwrap(), r.target);
            for pair in path.windows(2) {
                let d: i32 = (0..3).map(|i| (pair[0][i] - pair[1][i]).abs()).sum();
                assert_eq!(d, 1);
                assert!(!w.is_blocked(w.state_of(pair[1]).unwrap()));
            }
            assert!((t.steps_per_episode.len() as u32) < opts.episodes);
        }
    }
}

#[test]
fn distance_initial_q_finds_the_bfs_optimum_at_each_size() {
    // The optimum at every size, in far fewer environment steps than the paper's Q = 0
    // (measured in docs/PERFORMANCE.md).
    distance_initial_q_finds_the_bfs_optimum(QPrecision::F64);
}

#[test]
fn f32_distance_initial_q_finds_the_bfs_optimum_at_each_size() {
    // The same with f32 Q-values (learning.q_precision = "f32"); how often f32 and f64
    // learn the same path: docs/PERFORMANCE.md.
    distance_initial_q_finds_the_bfs_optimum(QPrecision::F32);
}

#[test]
fn fixed_episodes_stay_the_paper_default() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let o = Learning::from_scenario(&s);
    assert!(!o.episodes_auto);
    assert_eq!((o.episodes, o.epsilon_decay_episodes), (10000, 9900));
    assert_eq!(o.initial_q, InitialQ::Zero);
    // Re-gridding keeps the learner's start rule.
    assert_eq!(regrid(&s, 25.0).unwrap().learning.initial_q, InitialQ::Zero);
}

#[test]
fn physical_distances_and_errors() {
    // A file may give the safe distances in mm only.
    let mut v = serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap();
    let obj = v.as_object_mut().unwrap();
    obj.remove("terminal_safe_distance");
    obj.remove("arm_safe_distance");
    obj.insert("terminal_safe_distance_mm".into(), json!(96.0));
    obj.insert("arm_safe_distance_mm".into(), json!(76.0));
    let s = Scenario::from_json(&v.to_string()).unwrap();
    assert_eq!(s.terminal_safe_distance, 0.96);
    assert_eq!(s.arm_safe_distance, 0.76);
    v.as_object_mut().unwrap().remove("arm_safe_distance_mm");
    match Scenario::from_json(&v.to_string()) {
        Err(Error::ScenarioParse(m)) => assert!(m.contains("arm_safe_distance"), "{m}"),
        other => panic!("{other:?}"),
    }
    // A start that is not a cell centre of the new grid is an error naming it.
    let p = Scenario::builtin("paper_simple").unwrap();
    match regrid(&p, 30.0) {
        Err(Error::InvalidArgument { name, value, .. }) => {
            assert_eq!(name, "start");
            assert!(value.contains("-200"), "{value}");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        regrid(&p, 0.0),
        Err(Error::InvalidArgument { name, .. }) if name == "cell_mm"
    ));
}

#[test]
fn surface_box_counts_for_the_arm() {
    // A box around the base cuts every arm pose under both models.
    let mut s = Scenario::builtin("paper_simple").unwrap();
    s.obstacle_boxes_mm = vec![ObstacleBox {
        min_mm: [-20.0, -20.0, -20.0],
        max_mm: [20.0, 20.0, 20.0],
        distance_to: DistanceTo::Surface,
    }];
    let planner = PosePlanner::from_scenario(&s);
    assert!(!planner.cell_reachable(s.target));
    let free = PosePlanner::from_scenario(&Scenario::builtin("paper_simple").unwrap());
    assert!(free.cell_reachable(s.target));
}
