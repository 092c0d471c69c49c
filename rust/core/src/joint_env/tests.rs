use super::options::MODEL_KEYS;
use super::*;
use crate::env::EnvDefault;
use crate::options::{check_value, Domain, OptionValue, Options};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn model() -> JointModel {
    JointModel::new(
        &Scenario::builtin("paper_simple").unwrap(),
        JointOptions::default(),
    )
    .unwrap()
}

fn random_action(rng: &mut ChaCha8Rng) -> [f64; 6] {
    std::array::from_fn(|_| rng.random_range(-1.0..=1.0))
}

/// A random action around a drift held for a while, so that rollouts leave the start and
/// meet obstacles and limits (a pure random walk stays near beta_0).
fn drifting_action(rng: &mut ChaCha8Rng, drift: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| (drift[i] + rng.random_range(-0.3..=0.3)).clamp(-1.0, 1.0))
}

#[test]
fn table_and_options_agree() {
    for key in MODEL_KEYS {
        assert!(joint_option_info(key).is_some(), "{key} not in the table");
    }
    // Every model option set to a value in its domain is read back.
    let mut o = Options::new();
    for key in MODEL_KEYS {
        let v = match joint_option_info(key).unwrap().domain {
            Domain::Bool => OptionValue::Bool(false),
            Domain::Int { .. } => OptionValue::Int(7),
            _ => OptionValue::Float(0.25),
        };
        o.insert(key.to_string(), v);
    }
    let j = JointOptions::from_options(&o).unwrap();
    assert!(!j.assist);
    assert_eq!(j.max_episode_steps, 7);
    assert_eq!(j.link_radius_mm, Some(0.25));
    assert_eq!(j.progress_reward, 0.25);
    j.check().unwrap();
    JointOptions::default().check().unwrap();
    o.insert("num_envs".into(), OptionValue::Int(3));
    let e = JointOptions::from_options(&o).unwrap_err().to_string();
    assert!(e.contains("`num_envs`"), "{e}");
}

/// The table's defaults lie in their domains, are `None` exactly for the nullable keywords,
/// and are what `JointOptions::default()` holds (the model's keywords have no other
/// default).
#[test]
fn defaults_come_from_the_table() {
    for o in &JOINT_ENV_OPTIONS {
        match o.default.value() {
            None => assert!(
                JOINT_NULLABLE.contains(&o.key),
                "{} defaults to None",
                o.key
            ),
            Some(v) => {
                assert!(!JOINT_NULLABLE.contains(&o.key), "{} is nullable", o.key);
                check_value(o.key, &o.domain, &v).unwrap();
            }
        }
    }
    let d = JointOptions::default();
    let mut o = Options::new();
    for key in MODEL_KEYS {
        if let Some(v) = joint_option_default(key).unwrap().value() {
            o.insert(key.to_string(), v);
        }
    }
    // Setting every default explicitly changes nothing.
    assert_eq!(JointOptions::from_options(&o).unwrap(), d);
    assert_eq!(d.max_joint_step_deg, 2.0);
    assert_eq!(d.max_episode_steps, 500);
    assert_eq!(d.link_radius_mm, None);
    assert!(d.assist);
    assert_eq!(
        joint_option_default("num_envs"),
        Some(EnvDefault::Int(1)),
        "num_envs"
    );
    assert_eq!(joint_option_default("no_such_keyword"), None);
}

#[test]
fn scenario_defaults_and_errors() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let m = model();
    // paper_simple: centres model, d_p = 0.76 cells of 100 mm -> 76 - 50 mm.
    assert_eq!(m.link_radius_mm(), 0.0);
    assert!((m.safe_distance_mm() - 26.0).abs() < 1e-9);
    assert_eq!(m.num_links(), 5);
    assert_eq!(m.obs_dim(), 27);
    assert_eq!(m.limits_rad()[0], [-PI, PI]);
    // Joint limits that exclude beta_0.
    let mut bad = s.clone();
    let mut lim = [[-180.0, 180.0]; 6];
    lim[2] = [-90.0, 90.0];
    bad.arm.joint_limits_deg = Some(lim);
    let e = JointModel::new(&bad, JointOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("arm.beta0_deg[2]"), "{e}");
    // A safe distance beta_0 does not keep.
    let e = JointModel::new(
        &s,
        JointOptions {
            safe_distance_mm: Some(60.0),
            ..JointOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("start pose is not clear"), "{e}");
    let e = JointModel::new(
        &s,
        JointOptions {
            max_joint_step_deg: 0.0,
            ..JointOptions::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("`max_joint_step_deg` = 0"), "{e}");
}

use std::f64::consts::PI;

#[test]
fn observation_fields() {
    let m = model();
    let ep = JointEpisode::new(&m);
    let mut obs = vec![0f32; m.obs_dim()];
    ep.write_obs(&m, &mut obs);
    let lay = m.obs_layout();
    let q = m.beta0_rad();
    let p = m.arm().fk(&q).position_mm;
    for i in 0..3 {
        assert_eq!(obs[lay.terminal.start + i], (p[i] / m.reach_mm()) as f32);
        assert_eq!(
            obs[lay.target.start + i],
            (m.target_mm()[i] / m.reach_mm()) as f32
        );
    }
    for i in 0..6 {
        assert_eq!(obs[lay.sin.start + i], q[i].sin() as f32);
        assert_eq!(obs[lay.cos.start + i], q[i].cos() as f32);
    }
    // beta_0's smallest gap is 50 mm (a link touches no cube closer): 50 / (50 + 26).
    let gmin = ep.clearance_mm(&m);
    assert!((gmin - 50.0).abs() < 1e-6, "{gmin}");
    let cmin = obs[lay.clearance.clone()]
        .iter()
        .copied()
        .fold(1.0f32, f32::min);
    assert!((cmin - (50.0 / 76.0) as f32).abs() < 1e-6);
    let dir = &obs[lay.direction.clone()];
    let n: f32 = dir.iter().map(|v| v * v).sum::<f32>().sqrt();
    assert!((n - 1.0).abs() < 1e-6);
    assert_eq!(obs[lay.refused], 0.0);
}

/// Push the arm into an obstacle: eventually a step is refused, and a refused step leaves
/// the joints, the observation (but its refused flag) and the terminal unchanged.
#[test]
fn refused_step_leaves_state() {
    let m = model();
    let mut ep = JointEpisode::new(&m);
    let a = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0];
    let mut refused = 0;
    let mut obs0 = vec![0f32; m.obs_dim()];
    let mut obs1 = obs0.clone();
    for _ in 0..200 {
        let q0 = ep.joints_rad();
        ep.write_obs(&m, &mut obs0);
        let out = ep.step(&m, &a).unwrap();
        ep.write_obs(&m, &mut obs1);
        if out.refused {
            refused += 1;
            assert_eq!(ep.joints_rad(), q0);
            let r = m.obs_layout().refused;
            assert_eq!(obs1[r], 1.0);
            assert_eq!(obs0[..r], obs1[..r]);
            assert_eq!(out.reward, -1.0 - if refused > 1 { 2.0 } else { 0.0 });
        } else {
            assert_ne!(ep.joints_rad(), q0);
        }
    }
    assert!(refused > 10, "{refused}");
}

/// Joint 2 stopped by a tight joint limit: refused, with no interpolation.
#[test]
fn joint_limits_refuse() {
    let mut s = Scenario::builtin("paper_simple").unwrap();
    let b = s.arm.beta0_deg;
    let mut lim = [[-180.0, 180.0]; 6];
    lim[5] = [b[5] - 3.0, b[5] + 3.0];
    s.arm.joint_limits_deg = Some(lim);
    let m = JointModel::new(&s, JointOptions::default()).unwrap();
    let mut ep = JointEpisode::new(&m);
    let a = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    assert!(!ep.step(&m, &a).unwrap().refused);
    let out = ep.step(&m, &a).unwrap();
    assert!(out.refused && out.substeps == 0);
    assert!((ep.joints_rad()[5] - (b[5] + 2.0).to_radians()).abs() < 1e-12);
}

/// Random rollouts: every accepted step keeps, at an interpolation 8 times finer than the
/// env's, a gap of at least `(1 - substep_fraction / 2) * safe_distance` (the documented
/// bound), and no checked pose is closer than the safe distance; every end pose within
/// limits.
#[test]
fn accepted_steps_keep_clear() {
    let m = model();
    let s = m.safe_distance_mm();
    let floor = (1.0 - m.options().substep_fraction / 2.0) * s;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut ep = JointEpisode::new(&m);
    let (mut accepted, mut refused) = (0, 0);
    let mut drift = [0.0; 6];
    for step in 0..4000 {
        if step % 400 == 0 {
            ep.reset(&m);
        }
        if step % 40 == 0 {
            drift = random_action(&mut rng);
        }
        let q0 = ep.joints_rad();
        let out = ep.step(&m, &drifting_action(&mut rng, &drift)).unwrap();
        if out.refused {
            refused += 1;
            continue;
        }
        accepted += 1;
        let q1 = ep.joints_rad();
        assert!(m.within_limits(&q1));
        let n = 8 * m.substeps(&q0, &q1);
        for k in 1..=n {
            let f = k as f64 / n as f64;
            let q: Joints = std::array::from_fn(|i| q0[i] + (q1[i] - q0[i]) * f);
            let p = m.arm().points_mm(&q);
            let gap = m.clearance().capsules_gap_mm(&p, m.link_radius_mm());
            assert!(gap >= floor, "step {step}: gap {gap} < {floor}");
            if k % 8 == 0 {
                assert!(gap > s, "step {step}: checked pose gap {gap} <= {s}");
            }
        }
    }
    assert!(accepted > 1000 && refused > 100, "{accepted} / {refused}");
}

/// The sub-step bound: no polyline point moves more than `substep_fraction * safe_distance`
/// between two consecutive sub-steps of a full-size step.
#[test]
fn substep_bound_holds() {
    let m = model();
    let per = m.options().substep_fraction * m.safe_distance_mm();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..300 {
        let q0: Joints = std::array::from_fn(|_| rng.random_range(-PI..PI));
        let a = random_action(&mut rng);
        let q1: Joints = std::array::from_fn(|i| q0[i] + a[i] * m.max_step_rad);
        let n = m.substeps(&q0, &q1);
        let at = |k: u32| {
            let f = k as f64 / n as f64;
            m.arm()
                .points_mm(&std::array::from_fn(|i| q0[i] + (q1[i] - q0[i]) * f))
        };
        for k in 0..n {
            let (p, r) = (at(k), at(k + 1));
            for j in 0..8 {
                assert!((p[j] - r[j]).norm() <= per + 1e-9);
            }
        }
    }
}

/// A batch of N is N episodes with next-step autoreset and the step cap, and its rewards
/// equal `goal_rewards` of its own goals to the bit.
#[test]
fn batch_matches_episodes() {
    let opts = JointOptions {
        max_episode_steps: 37,
        ..JointOptions::default()
    };
    let m = Arc::new(JointModel::new(&Scenario::builtin("paper_simple").unwrap(), opts).unwrap());
    let n = 3;
    let d = m.obs_dim();
    let mut batch = JointBatch::new(m.clone(), n).unwrap();
    let mut eps: Vec<JointEpisode> = (0..n).map(|_| JointEpisode::new(&m)).collect();
    let mut done = vec![false; n];
    let (mut obs, mut rw) = (vec![0f32; n * d], vec![0f64; n]);
    let (mut te, mut tr, mut rf) = (vec![false; n], vec![false; n], vec![false; n]);
    let (mut dist, mut cl, mut dp) = (vec![0f64; n], vec![0f64; n], vec![0f64; n]);
    let (mut jo, mut tm, mut pg) = (vec![0f64; 6 * n], vec![0f64; 3 * n], vec![0f32; 3 * n]);
    macro_rules! bufs {
        () => {
            JointBuffers {
                obs: &mut obs,
                rewards: &mut rw,
                terminated: &mut te,
                truncated: &mut tr,
                refused: &mut rf,
                distance_mm: &mut dist,
                clearance_mm: &mut cl,
                detour_penalty: &mut dp,
                joints: &mut jo,
                terminal_mm: &mut tm,
                previous_goal: &mut pg,
            }
        };
    }
    batch.reset(None, bufs!()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut one = vec![0f32; d];
    let mut truncations = 0;
    for _ in 0..120 {
        let acts: Vec<f64> = (0..6 * n).map(|_| rng.random_range(-1.0..=1.0)).collect();
        batch.step(&acts, bufs!()).unwrap();
        for i in 0..n {
            if done[i] {
                eps[i].reset(&m);
                done[i] = false;
                assert_eq!((rw[i], te[i], tr[i]), (0.0, false, false));
            } else {
                let a: [f64; 6] = std::array::from_fn(|k| acts[6 * i + k]);
                let out = eps[i].step(&m, &a).unwrap();
                assert_eq!(out.reward, rw[i]);
                assert_eq!(out.refused, rf[i]);
                let trunc = !out.reached && eps[i].steps() >= 37;
                assert_eq!(tr[i], trunc);
                truncations += usize::from(trunc);
                done[i] = out.reached || trunc;
                let own = m
                    .goal_rewards(
                        &pg[3 * i..3 * i + 3],
                        &obs[i * d + 12..i * d + 15],
                        &obs[i * d + 15..i * d + 18],
                        &[rf[i]],
                        &[dp[i]],
                    )
                    .unwrap();
                assert_eq!(own[0].to_bits(), rw[i].to_bits());
            }
            eps[i].write_obs(&m, &mut one);
            assert_eq!(&obs[i * d..(i + 1) * d], &one[..]);
            assert_eq!(&jo[6 * i..6 * i + 6], &eps[i].joints_rad()[..]);
        }
    }
    assert!(truncations >= n * 2, "{truncations}");
    // Bad actions are refused before any lane moves, naming the lane.
    let mut acts = vec![0.0; 6 * n];
    acts[8] = 1.5;
    let e = batch.step(&acts, bufs!()).unwrap_err().to_string();
    assert!(e.contains("`actions[1]` = 1.5 at joint 2"), "{e}");
}

/// Progress toward the target is rewarded: a step that reduces the distance by x mm earns
/// `progress_reward * x - step_penalty`.
#[test]
fn reward_mapping() {
    let m = model();
    let mut ep = JointEpisode::new(&m);
    let d0 = ep.distance_to_target_mm(&m);
    let out = ep.step(&m, &[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert!(!out.refused);
    let d1 = ep.distance_to_target_mm(&m);
    let want = 0.05 * (d0 - d1) - 0.02;
    assert!(
        (out.reward - want).abs() < 1e-12,
        "{} vs {want}",
        out.reward
    );
    // Without assist: eq. 5 alone.
    let plain = JointModel::new(
        &Scenario::builtin("paper_simple").unwrap(),
        JointOptions {
            assist: false,
            reward_scale: 2.0,
            ..JointOptions::default()
        },
    )
    .unwrap();
    let mut ep = JointEpisode::new(&plain);
    let out = ep.step(&plain, &[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    assert_eq!(out.reward, -0.04);
}

/// The env's check (`check_move`: closed-form distances, motion bounds, skipped poses)
/// gives the reference's answer (every sub-step measured by parry) on long drifting
/// rollouts, and the observation's link gaps equal the parry reference within 1e-9 mm:
/// paper_simple, the same world with capsules of radius 10 mm, and a generated world.
#[test]
fn fast_check_equals_the_parry_reference() {
    let s = Scenario::builtin("paper_simple").unwrap();
    let generated = crate::generator::generate(&crate::generator::GeneratorOptions::default(), 3)
        .expect("generated world 3");
    let thick = JointOptions {
        link_radius_mm: Some(10.0),
        safe_distance_mm: Some(12.0),
        ..JointOptions::default()
    };
    let worlds = [
        (JointModel::new(&s, JointOptions::default()).unwrap(), 1u64),
        (JointModel::new(&s, thick).unwrap(), 2),
        (
            JointModel::new(&generated, JointOptions::default()).unwrap(),
            3,
        ),
    ];
    for (m, seed) in &worlds {
        let mut rng = ChaCha8Rng::seed_from_u64(*seed);
        let mut ep = JointEpisode::new(m);
        let (mut refused, mut accepted, mut near) = (0, 0, 0);
        let mut drift = [0.0; 6];
        for step in 0..6000 {
            if step % 300 == 0 {
                ep.reset(m);
            }
            if step % 30 == 0 {
                drift = random_action(&mut rng);
            }
            let a = drifting_action(&mut rng, &drift);
            let q0 = ep.joints_rad();
            let to: Joints = std::array::from_fn(|i| q0[i] + a[i] * m.max_step_rad);
            let want = m.within_limits(&to) && m.motion_is_clear(&q0, &to);
            let out = ep.step(m, &a).unwrap();
            assert_eq!(out.refused, !want, "seed {seed}, step {step}");
            if out.refused {
                refused += 1;
                continue;
            }
            accepted += 1;
            let mut reference = [0.0; MAX_LINKS];
            let nl = m.num_links();
            m.link_gaps_mm(&m.arm().points_mm(&ep.joints_rad()), &mut reference[..nl]);
            for (g, r) in ep.link_gaps_mm(m).iter().zip(&reference) {
                assert!(
                    (g - r).abs() <= 1e-9,
                    "seed {seed}, step {step}: {g} vs {r}"
                );
            }
            near += usize::from(ep.clearance_mm(m) < 2.0 * m.safe_distance_mm());
        }
        // Both answers, and steps close to the obstacles where the bounds cannot decide.
        assert!(
            refused > 300 && accepted > 1000 && near > 100,
            "seed {seed}: {refused} refused, {accepted} accepted, {near} near"
        );
    }
}

/// The per-link motion bound of `check_move`: between two poses of a move at fractions t
/// and t', no point of link k moves farther than `P_k |t - t'|`, with
/// `P_k = Σ_i |Δq_i| ℓ_{i,k}` (checked on each link's ends and middle, 64 steps per move).
#[test]
fn link_motion_bound_holds() {
    let m = model();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..300 {
        let q0: Joints = std::array::from_fn(|_| rng.random_range(-PI..PI));
        let a = random_action(&mut rng);
        let q1: Joints = std::array::from_fn(|i| q0[i] + a[i] * m.max_step_rad);
        let at = |k: u32| {
            let f = k as f64 / 64.0;
            m.arm()
                .points_mm(&std::array::from_fn(|i| q0[i] + (q1[i] - q0[i]) * f))
        };
        for (l, &k) in m.links().iter().enumerate() {
            let p: f64 = (0..6)
                .map(|i| (q1[i] - q0[i]).abs() * m.link_lever_mm[l][i])
                .sum();
            assert!(p <= m.path_bound_mm(&q0, &q1) + 1e-9);
            for s in 0..64 {
                let (x, y) = (at(s), at(s + 1));
                for w in [0.0, 0.5, 1.0] {
                    let u = x[k] + (x[k + 1] - x[k]) * w;
                    let v = y[k] + (y[k + 1] - y[k]) * w;
                    assert!((u - v).norm() <= p / 64.0 + 1e-9, "link {k}");
                }
            }
        }
    }
}
