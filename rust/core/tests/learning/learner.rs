//! The learner (eqs. 7-8): determinism, the paper's scenarios, options.

use super::*;

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
