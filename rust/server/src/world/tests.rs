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
    assert!(check_shape(&[], &[], 1).is_ok());
    assert!(check_shape(&[1], &[], 1).is_err());
    assert!(check_shape(&[4], &[4], 4).is_ok());
    assert!(check_shape(&[4], &[4], 1).is_ok());
    assert!(check_shape(&[-1], &[4], 4).is_ok());
    assert!(check_shape(&[-1], &[4], 3).is_err());
    assert!(check_shape(&[4], &[4], 3).is_err());
    assert!(check_shape(&[-1, -1], &[4], 4).is_err());
}
