use super::*;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn model(random_target: bool) -> Arc<EnvModel> {
    let s = Scenario::builtin("paper_simple").unwrap();
    Arc::new(
        EnvModel::new(
            &s,
            EnvOptions {
                random_target,
                ..EnvOptions::for_scenario(&s)
            },
        )
        .unwrap(),
    )
}

#[test]
fn episode_follows_grid_world() {
    let m = model(false);
    let mut ep = Episode::new(&m);
    ep.reset(&m);
    let w = m.world().clone();
    let mut s = w.start();
    let mut last = None;
    for a in [5usize, 5, 3, 2, 2, 2, 0, 0, 1, 4] {
        let t = w.step(s, a, last, Assist::on());
        let o = ep.step(&m, a);
        assert_eq!(o.reward, t.reward);
        assert_eq!(o.collided, t.collided);
        s = t.next;
        last = if t.collided { Some(a) } else { None };
        assert_eq!(ep.state(), s);
    }
    let mut obs = [0f32; VECTOR_OBS_DIM];
    ep.write_vector_obs(&m, &mut obs);
    assert!(obs.iter().all(|v| (-1.0..=1.0).contains(v)));
}

#[test]
fn shortest_path_terminates_with_target_reward() {
    let m = model(false);
    let w = m.world();
    let path = w.shortest_path().unwrap();
    let mut ep = Episode::new(&m);
    ep.reset(&m);
    let mut last = None;
    for pair in path.windows(2) {
        let d = [0, 1, 2].map(|i| pair[1][i] - pair[0][i]);
        let a = crate::grid::ACTIONS.iter().position(|m| *m == d).unwrap();
        last = Some(ep.step(&m, a));
    }
    assert!(last.unwrap().reached);
    assert_eq!(ep.distance_to_target(&m), 0.0);
}

#[test]
fn goal_rewards_equal_step_rewards_to_the_bit() {
    for (random_target, assist, scale) in [
        (true, Assist::on(), 1.0),
        (true, Assist::off(), 1e-4),
        (false, Assist::on(), 0.3),
    ] {
        let s = Scenario::builtin("paper_simple").unwrap();
        let m = EnvModel::new(
            &s,
            EnvOptions {
                random_target,
                assist,
                reward_scale: scale,
                ..EnvOptions::for_scenario(&s)
            },
        )
        .unwrap();
        let mut ep = Episode::new(&m);
        ep.seed(7);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (mut ach, mut des, mut col, mut det, mut want) =
            (vec![], vec![], vec![], vec![], vec![]);
        let mut collisions = 0;
        for _ in 0..20 {
            ep.reset(&m);
            for _ in 0..30 {
                let out = ep.step(&m, rng.random_range(0..NUM_ACTIONS));
                let mut obs = [0f32; VECTOR_OBS_DIM];
                ep.write_vector_obs(&m, &mut obs);
                ach.extend(obs[OBS_TERMINAL].iter().map(|&v| v as f64));
                des.extend(obs[OBS_TARGET].iter().map(|&v| v as f64));
                col.push(out.collided);
                det.push(out.detour_penalty);
                want.push(out.reward);
                collisions += out.collided as usize;
                if out.reached {
                    break;
                }
            }
        }
        assert!(collisions > 0);
        let got = m.goal_rewards(&ach, &des, &col, &det).unwrap();
        assert_eq!(
            got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            want.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

#[test]
fn goal_rewards_relabel_and_check_their_inputs() {
    let m = model(false);
    let w = m.world();
    let t = m.normalised(w.target()).map(f64::from);
    let r = m.goal_rewards(&t, &t, &[false], &[0.0]).unwrap();
    // Reaching the desired cell: +r plus eq. 10's r_e * d_o (d_t = 0).
    assert_eq!(r[0], 20000.0 + 40.0 * w.start_distance_cells());
    let c = m.goal_rewards(&t, &t, &[true], &[0.0]).unwrap();
    assert_eq!(c[0], -8000.0 + 40.0 * w.start_distance_cells());
    let err = m.goal_rewards(&t, &t[..2], &[false], &[0.0]).unwrap_err();
    assert!(err.to_string().contains("desired_goal"), "{err}");
    let err = m
        .goal_rewards(&[2.0, 0.0, 0.0], &t, &[false], &[0.0])
        .unwrap_err();
    assert!(err.to_string().contains("achieved_goal"), "{err}");
    let err = m.goal_rewards(&t, &t, &[false], &[f64::NAN]).unwrap_err();
    assert!(err.to_string().contains("detour_penalty"), "{err}");
    for s in 0..w.num_states() {
        assert_eq!(m.goal_cell(m.normalised(s).map(f64::from)), w.cell_of(s));
    }
}

#[test]
fn arm_aware_cells() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let cells = unreachable_cells(&s).unwrap();
    assert!(!cells.contains(&s.start) && !cells.contains(&s.target));
    assert!(!cells.iter().any(|c| s.obstacles.contains(c)));
    let planner = PosePlanner::from_scenario(&s);
    for c in &cells {
        assert!(first_clear_pose(&planner, s.cell_mm, *c).is_none());
    }
    let q = first_clear_pose(&planner, s.cell_mm, s.target).expect("the target is reachable");
    let p = planner.arm().fk(&q).position_mm;
    assert!((p - s.cell_centre_mm(s.target)).norm() < 1e-6);
    // The arm-aware model blocks those cells.
    let m = EnvModel::new(
        &s,
        EnvOptions {
            extra_obstacles: cells.clone(),
            ..EnvOptions::for_scenario(&s)
        },
    )
    .unwrap();
    for c in &cells {
        assert!(m.world().is_blocked(m.world().state_of(*c).unwrap()));
    }
}

#[test]
fn batch_truncates_and_autoresets_next_step() {
    let m = model(true);
    let n = 3;
    let mut b = BatchEnv::new(m, n, 4).unwrap();
    b.seed(&[1, 2, 3]).unwrap();
    let mut out = BatchOutputs::new(n, false);
    b.reset(None, out.buffers()).unwrap();
    for k in 1..=4 {
        b.step(&[1u8, 1, 1], out.buffers()).unwrap();
        assert_eq!(out.truncated, vec![k == 4; n]);
    }
    b.step(&[1u8, 1, 1], out.buffers()).unwrap();
    assert_eq!(out.rewards, vec![0.0; n]);
    assert!(b.episodes().iter().all(|e| e.steps() == 0));
    assert!(b.step(&[6u8, 0, 0], out.buffers()).is_err());
}

#[test]
fn env_defaults_are_in_their_domains_and_none_exactly_for_the_nullable_keywords() {
    for o in &ENV_OPTIONS {
        match o.default.value() {
            None => assert!(ENV_NULLABLE.contains(&o.key), "{} defaults to None", o.key),
            Some(v) => {
                assert!(!ENV_NULLABLE.contains(&o.key), "{} is nullable", o.key);
                check_value(o.key, &o.domain, &v).unwrap();
            }
        }
    }
    let s = Scenario::builtin("paper_simple").unwrap();
    let opts = EnvOptions::for_scenario(&s);
    assert_eq!(opts.assist, Assist::from_scenario(&s));
    assert_eq!(opts.reward_scale, 1.0);
    assert!(!opts.random_target && opts.extra_obstacles.is_empty());
}
