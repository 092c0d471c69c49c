//! Scenario parsing and validation: every bad input gives an error naming the field and
//! the value; property tests over random valid and invalid edits.

use proptest::prelude::*;
use serde_json::{json, Value};
use sixaxis_core::scenario::{InitialQ, QPrecision, Scenario, BUILTIN_NAMES};
use sixaxis_core::Error;

fn base() -> Value {
    serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap()
}

fn parse(v: &Value) -> Result<Scenario, Error> {
    Scenario::from_json(&v.to_string())
}

/// Apply `edit` to paper_simple and expect an InvalidScenario naming `field` and containing `value`.
fn expect_invalid(edit: impl FnOnce(&mut Value), field: &str, value: &str) {
    let mut v = base();
    edit(&mut v);
    match parse(&v) {
        Err(Error::InvalidScenario {
            field: f,
            value: val,
            reason,
        }) => {
            assert_eq!(f, field, "reason: {reason}");
            assert!(
                val.contains(value),
                "value {val:?} should contain {value:?}"
            );
        }
        other => panic!("expected InvalidScenario for {field}, got {other:?}"),
    }
}

#[test]
fn malformed_json_is_a_parse_error() {
    let e = Scenario::from_json("{\"name\": \"x\",").unwrap_err();
    assert!(matches!(e, Error::ScenarioParse(_)), "{e}");
    assert!(e.to_string().contains("line"), "{e}");
}

#[test]
fn unknown_field_is_named() {
    let mut v = base();
    v["rewards"]["bonus"] = json!(1.0);
    let e = parse(&v).unwrap_err().to_string();
    assert!(e.contains("bonus"), "{e}");
    let mut v = base();
    v["colour"] = json!("red");
    let e = parse(&v).unwrap_err().to_string();
    assert!(e.contains("colour"), "{e}");
}

#[test]
fn wrong_type_is_a_parse_error() {
    let mut v = base();
    v["start"] = json!("here");
    assert!(matches!(parse(&v), Err(Error::ScenarioParse(_))));
}

#[test]
fn nan_and_negative_values_are_rejected() {
    // JSON has no NaN literal; serde_json maps NaN to null, which fails to parse as f64.
    let mut v = base();
    v["arm_safe_distance"] = json!(null);
    assert!(matches!(parse(&v), Err(Error::ScenarioParse(_))));
    // A NaN given through the Rust API is caught by validate().
    let mut s = Scenario::builtin("paper_simple").unwrap();
    s.terminal_safe_distance = f64::NAN;
    match s.validate() {
        Err(Error::InvalidScenario { field, value, .. }) => {
            assert_eq!(field, "terminal_safe_distance");
            assert_eq!(value, "NaN");
        }
        other => panic!("{other:?}"),
    }
    expect_invalid(
        |v| v["arm_safe_distance"] = json!(-0.5),
        "arm_safe_distance",
        "-0.5",
    );
    expect_invalid(
        |v| v["rewards"]["step_penalty"] = json!(-1.0),
        "rewards.step_penalty",
        "-1",
    );
    expect_invalid(
        |v| v["rewards"]["distance_reward"] = json!(-40.0),
        "rewards.distance_reward",
        "-40",
    );
    expect_invalid(|v| v["cell_mm"] = json!(0.0), "cell_mm", "0");
    // d_s may exceed a cell (a re-gridded paper world), but then the target (0,3,0) lies
    // within 1.5 cells of the cube at (-1,3,1): the error names the target.
    expect_invalid(
        |v| v["terminal_safe_distance"] = json!(1.5),
        "target",
        "[0, 3, 0]",
    );
    expect_invalid(
        |v| v["terminal_safe_distance_mm"] = json!(50.0),
        "terminal_safe_distance_mm",
        "50",
    );
    expect_invalid(
        |v| v["obstacle_boxes_mm"] = json!([{"min_mm": [0, 0, 0], "max_mm": [-1, 5, 5]}]),
        "obstacle_boxes_mm[0]",
        "min_mm",
    );
    expect_invalid(
        |v| {
            v["obstacle_boxes_mm"] =
                json!([{"min_mm": [0, 0, 0], "max_mm": [10, 20, 10], "distance_to": "centre"}])
        },
        "obstacle_boxes_mm[0]",
        "max_mm",
    );
    expect_invalid(
        |v| v["learning"]["alpha"] = json!(0.0),
        "learning.alpha",
        "0",
    );
    expect_invalid(
        |v| v["learning"]["gamma"] = json!(1.5),
        "learning.gamma",
        "1.5",
    );
    expect_invalid(
        |v| v["learning"]["epsilon_start"] = json!(2.0),
        "learning.epsilon_start",
        "2",
    );
    expect_invalid(
        |v| v["learning"]["episodes"] = json!(0),
        "learning.episodes",
        "0",
    );
    expect_invalid(
        |v| v["planning"]["interpolation_steps"] = json!(0),
        "planning.interpolation_steps",
        "0",
    );
}

#[test]
fn start_and_target_placement() {
    expect_invalid(|v| v["start"] = json!([0, 1, 0]), "start", "[0, 1, 0]");
    expect_invalid(|v| v["target"] = json!([1, 1, 1]), "target", "[1, 1, 1]");
    expect_invalid(|v| v["target"] = json!([0, 30, 0]), "target", "[0, 30, 0]");
    expect_invalid(|v| v["start"] = json!([9, -2, 4]), "start", "[9, -2, 4]");
    expect_invalid(|v| v["target"] = json!([0, -2, 4]), "target", "[0, -2, 4]");
}

#[test]
fn empty_bounds() {
    expect_invalid(
        |v| v["bounds"] = json!({"min": [0, 0, 0], "max": [-1, 5, 5]}),
        "bounds",
        "min [0, 0, 0]",
    );
}

#[test]
fn beta0_must_reach_the_start() {
    expect_invalid(
        |v| v["arm"]["beta0_deg"][0] = json!(10.0),
        "arm.beta0_deg",
        "10.0",
    );
    // Moving the start without a matching beta_0 is caught the same way.
    expect_invalid(
        |v| v["start"] = json!([0, -2, 3]),
        "arm.beta0_deg",
        "57.9948",
    );
}

#[test]
fn dh_table_outside_the_closed_form_family() {
    expect_invalid(
        |v| v["arm"]["dh"][1]["alpha_deg"] = json!(45.0),
        "arm.dh",
        "table",
    );
    expect_invalid(
        |v| {
            v["arm"]["dh"]
                .as_array_mut()
                .unwrap()
                .pop()
                .map(|_| ())
                .unwrap()
        },
        "arm.dh",
        "5 rows",
    );
}

#[test]
fn joint_limits_must_be_ordered() {
    expect_invalid(
        |v| {
            v["arm"]["joint_limits_deg"] = json!([
                [-180, 180],
                [10, -10],
                [-180, 180],
                [-180, 180],
                [-180, 180],
                [-180, 180]
            ])
        },
        "arm.joint_limits_deg[1]",
        "[10, -10]",
    );
}

#[test]
fn planning_mode_and_nd_rule_are_validated() {
    expect_invalid(
        |v| v["planning"]["orientation_divisions_growth"] = json!(0),
        "planning.orientation_divisions_growth",
        "0",
    );
    // The cap must be at least the first n_d ...
    expect_invalid(
        |v| v["planning"]["orientation_divisions_max"] = json!(4),
        "planning.orientation_divisions_max",
        "4",
    );
    // ... at most 72 ...
    expect_invalid(
        |v| v["planning"]["orientation_divisions_max"] = json!(128),
        "planning.orientation_divisions_max",
        "128",
    );
    // ... and on the chain 8, 16, 32, 64 so that every grid contains the one before.
    expect_invalid(
        |v| v["planning"]["orientation_divisions_max"] = json!(48),
        "planning.orientation_divisions_max",
        "48",
    );
    let mut v = base();
    v["planning"]["orientation_divisions_growth"] = json!(1);
    v["planning"]["orientation_divisions_max"] = json!(48);
    assert!(
        parse(&v).is_ok(),
        "with n_d fixed the cap only has to be >= n_d"
    );
    let mut v = base();
    v["planning"]["mode"] = json!("greedy");
    let e = parse(&v).unwrap_err().to_string();
    assert!(
        e.contains("greedy") && e.contains("paper") && e.contains("backtracking"),
        "{e}"
    );
    for mode in ["paper", "backtracking"] {
        let mut v = base();
        v["planning"]["mode"] = json!(mode);
        assert_eq!(parse(&v).unwrap().planning.mode.name(), mode);
    }
}

#[test]
fn initial_q_rule_is_validated() {
    for rule in [InitialQ::Zero, InitialQ::Distance] {
        let mut v = base();
        v["learning"]["initial_q"] = json!(rule.name());
        assert_eq!(parse(&v).unwrap().learning.initial_q, rule);
    }
    // Absent: the paper's Q = 0.
    assert_eq!(parse(&base()).unwrap().learning.initial_q, InitialQ::Zero);
    let mut v = base();
    v["learning"]["initial_q"] = json!("optimistic");
    let e = parse(&v).unwrap_err().to_string();
    assert!(
        e.contains("`learning.initial_q` = optimistic: must be one of zero, distance"),
        "{e}"
    );
    let mut v = base();
    v["learning"]["initial_q"] = json!(0);
    let e = parse(&v).unwrap_err().to_string();
    assert!(e.contains("scenario could not be parsed"), "{e}");
}

#[test]
fn q_precision_is_validated() {
    for p in [QPrecision::F64, QPrecision::F32] {
        let mut v = base();
        v["learning"]["q_precision"] = json!(p.name());
        assert_eq!(parse(&v).unwrap().learning.q_precision, p);
    }
    // Absent: f64, so every file written before the field existed means the same run.
    let mut v = base();
    assert!(v["learning"]
        .as_object_mut()
        .unwrap()
        .remove("q_precision")
        .is_some());
    assert_eq!(parse(&v).unwrap().learning.q_precision, QPrecision::F64);
    for s in BUILTIN_NAMES {
        let sc = Scenario::builtin(s).unwrap();
        assert_eq!(sc.learning.q_precision, QPrecision::F64, "{s}");
    }
    for bad in ["f16", "double", ""] {
        let mut v = base();
        v["learning"]["q_precision"] = json!(bad);
        let e = parse(&v).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "`learning.q_precision` = {bad}: must be one of f64, f32"
            )),
            "{e}"
        );
    }
    let mut v = base();
    v["learning"]["q_precision"] = json!(32);
    assert!(parse(&v).is_err());
}

#[test]
fn load_by_name_path_and_unknown() {
    for name in BUILTIN_NAMES {
        assert_eq!(Scenario::load(name).unwrap().name, *name);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("mine.json");
    std::fs::write(&p, Scenario::builtin("paper_complex").unwrap().to_json()).unwrap();
    assert_eq!(
        Scenario::load(p.to_str().unwrap()).unwrap().name,
        "paper_complex"
    );
    match Scenario::load("no_such_scenario") {
        Err(Error::ScenarioNotFound { name, known }) => {
            assert_eq!(name, "no_such_scenario");
            assert!(known.contains("paper_simple"));
        }
        other => panic!("{other:?}"),
    }
    let missing = dir.path().join("absent.json");
    assert!(matches!(
        Scenario::load(missing.to_str().unwrap()),
        Err(Error::Io { .. })
    ));
}

#[test]
fn defaults_fill_a_short_file() {
    let short = json!({
        "name": "short", "cell_mm": 100.0,
        "bounds": {"min": [-3, -3, -2], "max": [3, 5, 5]},
        "start": [0, -2, 4], "target": [0, 3, 0], "obstacles": [[0, 1, 0]],
        "terminal_safe_distance": 0.96, "arm_safe_distance": 0.76
    });
    let s = parse(&short).unwrap();
    let paper = Scenario::builtin("paper_simple").unwrap();
    assert_eq!(s.rewards, paper.rewards);
    assert_eq!(s.learning, paper.learning);
    assert_eq!(s.arm, paper.arm);
    assert_eq!(s.planning, paper.planning);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any obstacle set that avoids start and target, inside any bounds that hold both,
    /// validates and survives a JSON round trip unchanged.
    #[test]
    fn valid_edits_roundtrip(
        obstacles in prop::collection::vec((-3i32..=3, -3i32..=5, -2i32..=5), 0..40),
        grow in (0i32..4, 0i32..4, 0i32..4),
        ds in 0.0f64..0.999,
        dp in 0.0f64..3.0,
    ) {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        s.obstacles = obstacles.into_iter().map(|(x, y, z)| [x, y, z])
            .filter(|c| *c != s.start && *c != s.target).collect();
        s.bounds.max = [s.bounds.max[0] + grow.0, s.bounds.max[1] + grow.1, s.bounds.max[2] + grow.2];
        s.terminal_safe_distance = ds;
        s.arm_safe_distance = dp;
        prop_assert!(s.validate().is_ok());
        let again = Scenario::from_json(&s.to_json()).unwrap();
        prop_assert_eq!(again, s);
    }

    /// A start or target placed on an obstacle, or outside the bounds, is always rejected
    /// with an error naming that field.
    #[test]
    fn misplaced_target_is_rejected(x in -10i32..10, y in -10i32..10, z in -10i32..10) {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        let c = [x, y, z];
        prop_assume!(c != s.start);
        s.target = c;
        let inside = s.bounds.contains(c);
        let blocked = s.obstacles.contains(&c);
        match s.validate() {
            Ok(()) => prop_assert!(inside && !blocked),
            Err(Error::InvalidScenario { field, .. }) => {
                prop_assert!(!inside || blocked);
                prop_assert_eq!(field, "target");
            }
            Err(e) => prop_assert!(false, "unexpected error {}", e),
        }
    }

    /// Negative or non-finite reward magnitudes are rejected naming the field.
    #[test]
    fn negative_rewards_rejected(which in 0usize..6, v in -1e9f64..-1e-9) {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        let names = ["target_reward", "step_penalty", "collision_penalty",
            "repeat_collision_penalty", "reverse_after_collision_penalty", "distance_reward"];
        let r = &mut s.rewards;
        let slot = [&mut r.target_reward, &mut r.step_penalty, &mut r.collision_penalty,
            &mut r.repeat_collision_penalty, &mut r.reverse_after_collision_penalty, &mut r.distance_reward];
        *slot.into_iter().nth(which).unwrap() = v;
        match s.validate() {
            Err(Error::InvalidScenario { field, .. }) => prop_assert_eq!(field, format!("rewards.{}", names[which])),
            other => prop_assert!(false, "expected rejection, got {:?}", other),
        }
    }
}

#[test]
fn envs_files_equal_the_built_in_copies() {
    // The crate compiles in rust/core/scenarios/*.json; envs/ holds the user-facing copies.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut in_envs: Vec<String> = std::fs::read_dir(root.join("../../envs"))
        .unwrap()
        .filter_map(|e| {
            let name = e.unwrap().file_name().into_string().unwrap();
            name.strip_suffix(".json").map(str::to_string)
        })
        .collect();
    in_envs.sort();
    let mut builtin: Vec<String> = sixaxis_core::scenario::BUILTIN_NAMES
        .iter()
        .map(|s| s.to_string())
        .collect();
    builtin.sort();
    assert_eq!(
        in_envs, builtin,
        "envs/ and the built-in scenarios list the same names"
    );
    for name in sixaxis_core::scenario::BUILTIN_NAMES {
        let envs = std::fs::read_to_string(root.join(format!("../../envs/{name}.json"))).unwrap();
        let own = std::fs::read_to_string(root.join(format!("scenarios/{name}.json"))).unwrap();
        assert_eq!(
            envs, own,
            "envs/{name}.json differs from rust/core/scenarios/{name}.json"
        );
        assert_eq!(
            Scenario::from_json(&envs).unwrap(),
            Scenario::builtin(name).unwrap()
        );
    }
}
