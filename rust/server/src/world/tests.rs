use super::*;
use crate::proto::Settings;

fn settings(pairs: &[(&str, Tensor)]) -> Settings {
    pairs
        .iter()
        .map(|(k, t)| (k.to_string(), t.clone()))
        .collect()
}

fn int(v: i64) -> Tensor {
    Tensor {
        payload: Some(Payload::Int64s(crate::proto::tensor::Int64Array {
            array: vec![v],
        })),
        shape: vec![],
    }
}

fn text(v: &str) -> Tensor {
    Tensor {
        payload: Some(Payload::Strings(StringArray {
            array: vec![v.into()],
        })),
        shape: vec![],
    }
}

#[test]
fn settings_are_checked_by_the_core_table() {
    let e = WorldSettings::from_settings(&settings(&[("num_envs", int(0))])).unwrap_err();
    assert_eq!(e.code, Code::InvalidArgument);
    assert!(e.message.contains("`num_envs` = 0"), "{}", e.message);
    let e = WorldSettings::from_settings(&settings(&[("obs_type", text("pixels"))])).unwrap_err();
    assert!(e.message.contains("`obs_type` = pixels"), "{}", e.message);
    let e = WorldSettings::from_settings(&settings(&[("colour", text("red"))])).unwrap_err();
    assert!(
        e.message.contains("`colour` = red: is no setting"),
        "{}",
        e.message
    );
    let e = WorldSettings::from_settings(&settings(&[("scenario", text("nowhere"))])).unwrap_err();
    assert_eq!(e.code, Code::NotFound);
    let e =
        WorldSettings::from_settings(&settings(&[("scenario", text("/etc/passwd"))])).unwrap_err();
    assert_eq!(e.code, Code::NotFound, "{}", e.message);
    let s = WorldSettings::from_settings(&settings(&[
        ("num_envs", int(4)),
        ("obs_type", text("goal")),
        ("seed", int(3)),
    ]))
    .unwrap();
    assert_eq!(
        (s.num_envs, s.obs_type, s.seed),
        (4, ObsType::Goal, Some(3))
    );
    assert_eq!(
        s.max_episode_steps,
        s.scenario.learning.max_steps_per_episode
    );
}

#[test]
fn shapes_follow_the_protocol() {
    let shape = |s: &[i32], want: &[i32], len| check_shape("action", s, want, len);
    assert!(shape(&[], &[], 1).is_ok());
    assert!(shape(&[1], &[], 1).is_err());
    assert!(shape(&[4], &[4], 4).is_ok());
    assert!(shape(&[4], &[4], 1).is_ok());
    assert!(shape(&[-1], &[4], 4).is_ok());
    assert!(shape(&[-1], &[4], 3).is_err());
    assert!(shape(&[4], &[4], 3).is_err());
    assert!(shape(&[-1, -1], &[4], 4).is_err());
    let e = check_shape("reset_mask", &[3], &[4], 3).unwrap_err();
    assert!(e.message.contains("`reset_mask`"), "{}", e.message);
}

fn bools(v: &[bool]) -> Tensor {
    Tensor {
        payload: Some(Payload::Bools(crate::proto::tensor::BoolArray {
            array: v.to_vec(),
        })),
        shape: vec![v.len() as i32],
    }
}

fn observations(w: &mut World) -> Vec<f32> {
    let r = w
        .step(&StepRequest {
            actions: BTreeMap::new(),
            requested_observations: vec![OBSERVATION],
        })
        .unwrap();
    match &r.observations[&OBSERVATION].payload {
        Some(Payload::Floats(f)) => f.array.clone(),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_reset_mask_restarts_only_its_lanes() {
    let s = WorldSettings::from_settings(&settings(&[
        ("num_envs", int(3)),
        (
            "random_target",
            Tensor {
                payload: Some(Payload::Bools(crate::proto::tensor::BoolArray {
                    array: vec![true],
                })),
                shape: vec![],
            },
        ),
        ("seed", int(5)),
    ]))
    .unwrap();
    let mut w = World::new(&s).unwrap();
    let first = observations(&mut w);
    let mut step = StepRequest {
        actions: BTreeMap::from([(
            ACTION,
            Tensor {
                payload: Some(Payload::Int32s(Int32Array {
                    array: vec![4, 4, 4],
                })),
                shape: vec![3],
            },
        )]),
        requested_observations: vec![OBSERVATION],
    };
    w.step(&step).unwrap();
    let moved = match &w.step(&step).unwrap().observations[&OBSERVATION].payload {
        Some(Payload::Floats(f)) => f.array.clone(),
        other => panic!("{other:?}"),
    };
    assert_ne!(moved, first);
    // Lane 1 restarts; lanes 0 and 2 are not stepped (the Step's actions are ignored).
    let reset = |mask: Tensor| ResetSettings {
        seed: None,
        reset_mask: Some(mask),
    };
    w.restart(&reset(bools(&[false, true, false]))).unwrap();
    let after = observations(&mut w);
    let d = VECTOR_OBS_DIM;
    assert_eq!(after[..d], moved[..d]);
    assert_eq!(after[2 * d..], moved[2 * d..]);
    assert_ne!(after[d..2 * d], moved[d..2 * d]);
    // A wrong mask is refused naming it, and leaves the world as it was.
    for bad in [bools(&[true, false]), int(1)] {
        let e = w.restart(&reset(bad)).unwrap_err();
        assert_eq!(e.code, Code::InvalidArgument);
        assert!(e.message.contains("`reset_mask`"), "{}", e.message);
    }
    step.requested_observations = vec![];
    w.step(&step).unwrap();
    let e = reset_settings(&settings(&[("lanes", int(1))])).unwrap_err();
    assert!(e.message.contains("seed, reset_mask"), "{}", e.message);
}
