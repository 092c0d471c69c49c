//! Mutation fuzzing of the core's two parsers of outside bytes: scenario JSON
//! ([`Scenario::from_json`]) and Q-table files ([`QTable::from_file_bytes`]). Every input
//! must give `Ok` or an `Err`, never a panic; an accepted scenario must validate, round
//! trip, and build its grid world; an accepted Q-table must hold finite values of the world.
//!
//! Inputs per target: `SIXAXIS_FUZZ_INPUTS` (default 3000, the CI run); the seed of the
//! mutation stream: `SIXAXIS_FUZZ_SEED` (default 0). `scripts/fuzz_long.sh` runs a million
//! per target. A failing input is printed (seed, index, text) so it can be replayed.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use sixaxis_core::qlearning::QTable;
use sixaxis_core::scenario::{QPrecision, Scenario, BUILTIN_NAMES};
use sixaxis_core::GridWorld;

fn knob(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.replace('_', "").parse().ok())
        .unwrap_or(default)
}

fn inputs() -> u64 {
    knob("SIXAXIS_FUZZ_INPUTS", 3000)
}

fn seed() -> u64 {
    knob("SIXAXIS_FUZZ_SEED", 0)
}

/// Tokens that have broken parsers before: limits of every integer type, non-numbers,
/// deep nesting, wrong types.
const TOKENS: &[&str] = &[
    "0",
    "-1",
    "2147483647",
    "2147483648",
    "-2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775809",
    "1e999",
    "-1e999",
    "1e-400",
    "NaN",
    "-0.0",
    "0.5",
    "1.7976931348623157e308",
    "null",
    "true",
    "\"\"",
    "\"\\u0000\"",
    "\"\\ud800\"",
    "[]",
    "{}",
    "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[",
    "{\"kind\":\"capsules\"}",
    "{\"kind\":\"centres\",\"x\":1}",
    "[0,0]",
    "[0,0,0,0]",
    "[-2147483648,-2147483648,-2147483648]",
    "[2147483647,2147483647,2147483647]",
];

/// A random JSON value of the kinds a scenario field may hold, and some it may not.
fn random_value(rng: &mut ChaCha8Rng, depth: u32) -> Value {
    match rng.random_range(0..10) {
        0 => Value::from(rng.random::<i64>()),
        1 => Value::from(rng.random_range(-4i64..12)),
        2 => {
            let extremes = [i32::MIN as i64, i32::MAX as i64, u32::MAX as i64, i64::MIN];
            Value::from(extremes[rng.random_range(0..extremes.len())])
        }
        3 => Value::from(rng.random::<u64>()),
        4 => serde_json::Number::from_f64(
            rng.random_range(-2.0..2.0) * 10f64.powi(rng.random_range(-8..8)),
        )
        .map_or(Value::Null, Value::Number),
        5 if depth < 4 => Value::Array(
            (0..rng.random_range(0..5))
                .map(|_| random_value(rng, depth + 1))
                .collect(),
        ),
        6 => Value::Array(
            (0..3)
                .map(|_| Value::from(rng.random_range(-3i64..6)))
                .collect(),
        ),
        7 => Value::Bool(rng.random()),
        8 => Value::String(
            ["", "x", "centres", "capsules", "paper_simple"][rng.random_range(0..5)].into(),
        ),
        _ => Value::Null,
    }
}

/// Replace, remove or add one node of the JSON tree (structure-aware mutation).
fn mutate_tree(v: &mut Value, rng: &mut ChaCha8Rng) {
    let descend = rng.random_bool(0.6);
    match v {
        Value::Object(m) if !m.is_empty() => {
            let keys: Vec<String> = m.keys().cloned().collect();
            let k = keys[rng.random_range(0..keys.len())].clone();
            if descend && (m[&k].is_object() || m[&k].is_array()) {
                return mutate_tree(m.get_mut(&k).expect("key exists"), rng);
            }
            match rng.random_range(0..6) {
                0 => {
                    m.remove(&k);
                }
                1 => {
                    m.insert(format!("{k}_unknown"), Value::from(1));
                }
                _ => {
                    let depth = rng.random_range(0..4);
                    m.insert(k, random_value(rng, depth));
                }
            }
        }
        Value::Array(a) if !a.is_empty() => {
            let i = rng.random_range(0..a.len());
            if descend && (a[i].is_object() || a[i].is_array()) {
                return mutate_tree(&mut a[i], rng);
            }
            match rng.random_range(0..4) {
                0 => {
                    a.remove(i);
                }
                1 => a.push(random_value(rng, 2)),
                _ => a[i] = random_value(rng, 2),
            }
        }
        other => *other = random_value(rng, 0),
    }
}

/// Byte-level mutation of a text: flip, delete, duplicate, insert a token, truncate.
fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut ChaCha8Rng) {
    for _ in 0..rng.random_range(1..4) {
        if bytes.is_empty() {
            bytes.push(b'{');
        }
        let i = rng.random_range(0..bytes.len());
        match rng.random_range(0..6) {
            0 => bytes[i] ^= 1 << rng.random_range(0..8),
            1 => {
                let j = (i + rng.random_range(1..32)).min(bytes.len());
                bytes.drain(i..j);
            }
            2 => {
                let j = (i + rng.random_range(1..32)).min(bytes.len());
                let chunk = bytes[i..j].to_vec();
                bytes.splice(i..i, chunk);
            }
            3 => bytes.truncate(i),
            4 => bytes[i] = rng.random(),
            _ => {
                let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                let j = (i + rng.random_range(0..8)).min(bytes.len());
                bytes.splice(i..j, t.iter().copied());
            }
        }
    }
}

/// What must hold for an accepted scenario; whether it was accepted.
fn check_scenario(text: &str) -> bool {
    let Ok(s) = Scenario::from_json(text) else {
        return false;
    };
    s.validate().expect("an accepted scenario validates");
    let again = Scenario::from_json(&s.to_json()).expect("an accepted scenario round trips");
    assert_eq!(again, s);
    if s.bounds.volume() <= 1 << 16 {
        let w = GridWorld::new(&s).expect("an accepted scenario builds its world");
        assert_eq!(w.num_states(), s.bounds.volume());
        let _ = w.shortest_path();
    }
    true
}

/// Run `n` inputs of `make_input` through `check` (which says whether the parser accepted
/// the input), catching panics; report the rate and how many inputs were accepted.
fn fuzz(
    target: &str,
    n: u64,
    mut make_input: impl FnMut(&mut ChaCha8Rng) -> Vec<u8>,
    check: impl Fn(&[u8]) -> bool,
) {
    let seed = seed();
    let t0 = Instant::now();
    // The default hook would print every caught panic; failures are reported below.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failure = None;
    let mut accepted = 0u64;
    for i in 0..n {
        let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ i);
        let input = make_input(&mut rng);
        match catch_unwind(AssertUnwindSafe(|| check(&input))) {
            Ok(ok) => accepted += u64::from(ok),
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                failure = Some((i, msg, String::from_utf8_lossy(&input).into_owned()));
                break;
            }
        }
    }
    std::panic::set_hook(hook);
    if let Some((i, msg, input)) = failure {
        panic!("{target}: input {i} (seed {seed}) panicked: {msg}\ninput:\n{input}");
    }
    let secs = t0.elapsed().as_secs_f64();
    eprintln!(
        "fuzz {target}: {n} inputs, {accepted} accepted, no panic, {secs:.1} s ({:.0} inputs/s, seed {seed})",
        n as f64 / secs.max(1e-9)
    );
}

#[test]
fn scenario_json_from_tree_mutations() {
    let bases: Vec<Value> = BUILTIN_NAMES
        .iter()
        .map(|n| serde_json::to_value(Scenario::builtin(n).unwrap()).unwrap())
        .collect();
    fuzz(
        "scenario JSON (tree mutations)",
        inputs(),
        |rng| {
            let mut v = bases[rng.random_range(0..bases.len())].clone();
            for _ in 0..rng.random_range(1..4) {
                mutate_tree(&mut v, rng);
            }
            v.to_string().into_bytes()
        },
        |bytes| check_scenario(std::str::from_utf8(bytes).expect("serde_json writes UTF-8")),
    );
}

#[test]
fn scenario_json_from_byte_mutations() {
    let bases: Vec<String> = BUILTIN_NAMES
        .iter()
        .map(|n| Scenario::builtin(n).unwrap().to_json())
        .collect();
    fuzz(
        "scenario JSON (byte mutations)",
        inputs(),
        |rng| {
            let mut b = bases[rng.random_range(0..bases.len())].clone().into_bytes();
            mutate_bytes(&mut b, rng);
            b
        },
        |bytes| std::str::from_utf8(bytes).is_ok_and(check_scenario),
    );
}

#[test]
fn qtable_bytes_from_mutations() {
    let dir = tempfile::tempdir().unwrap();
    let simple = GridWorld::new(&Scenario::builtin("paper_simple").unwrap()).unwrap();
    let other = GridWorld::new(&Scenario::builtin("replan_clutter").unwrap()).unwrap();
    // A saved table of each world in each precision (f64, f32), values made distinct so
    // flips change something.
    let mut files = Vec::new();
    for (i, w) in [&simple, &other].into_iter().enumerate() {
        let n = w.num_states();
        let q = QTable::from_values(n, (0..n * 6).map(|k| k as f64 * 0.5 - 7.0).collect()).unwrap();
        for (j, q) in [q.clone(), q.into_precision(QPrecision::F32).unwrap()]
            .iter()
            .enumerate()
        {
            let p = dir.path().join(format!("q{i}_{j}.bin"));
            q.save(&p, w).unwrap();
            files.push(std::fs::read(&p).unwrap());
        }
    }
    fuzz(
        "Q-table bytes",
        inputs(),
        |rng| {
            // Mostly paper_simple's own file (the header must pass to reach the body), some
            // of the other world's file (must be a mismatch, never accepted).
            let world = 2 * usize::from(rng.random_bool(0.2));
            let mut b = files[world + usize::from(rng.random_bool(0.5))].clone();
            if rng.random_bool(0.5) {
                // Flip bits in the header or the body...
                for _ in 0..rng.random_range(1..4) {
                    let i = rng.random_range(0..b.len());
                    b[i] ^= 1 << rng.random_range(0..8);
                }
            } else {
                mutate_bytes(&mut b, rng);
            }
            b
        },
        |bytes| {
            let Ok(q) = QTable::from_file_bytes(bytes, &simple, Path::new("fuzz.bin")) else {
                return false;
            };
            assert_eq!(q.num_states(), simple.num_states());
            assert!(q.values().iter().all(|v| v.is_finite()));
            true
        },
    );
}

/// The parsers' worst inputs, named: each must be an error (these panicked or crashed in
/// the bindings before the depth limit, the bounds overflow fix and the bounded reads).
#[test]
fn named_hostile_inputs_are_errors() {
    let mut v = serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap();
    v["bounds"] = serde_json::json!({"min": [i32::MIN, i32::MIN, i32::MIN], "max": [i32::MAX, i32::MAX, i32::MAX]});
    let e = Scenario::from_json(&v.to_string()).unwrap_err();
    assert!(e.to_string().contains("more than 16,777,216 cells"), "{e}");
    // 2^22 * 2^22 * 2^20 cells: the product wrapped to 0 in usize.
    v["bounds"] = serde_json::json!({"min": [-(1 << 21), -(1 << 21), -(1 << 19)], "max": [(1 << 21) - 1, (1 << 21) - 1, (1 << 19) - 1]});
    let e = Scenario::from_json(&v.to_string()).unwrap_err();
    assert!(e.to_string().contains("more than 16,777,216 cells"), "{e}");
    let deep = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
    assert!(Scenario::from_json(&deep).is_err());
    let world = GridWorld::new(&Scenario::builtin("paper_simple").unwrap()).unwrap();
    for bytes in [
        &b""[..],
        b"SIXAXIS-QTABLE 1\n",
        b"SIXAXIS-QTABLE 1\n{}\n",
        b"\xff\xfe",
    ] {
        assert!(QTable::from_file_bytes(bytes, &world, Path::new("x")).is_err());
    }
    #[cfg(unix)]
    {
        let e = Scenario::from_file(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("larger than"), "{e}");
        let e = QTable::load(Path::new("/dev/zero"), &world).unwrap_err();
        assert!(e.to_string().contains("larger than"), "{e}");
    }
}

/// A parse error names the field at fault (serde_path_to_error), not just a line and column.
#[test]
fn parse_errors_name_the_field() {
    let mut v = serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap();
    v["learning"]["alpha"] = Value::from("fast");
    let e = Scenario::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("field `learning.alpha`"), "{e}");
    let mut v = serde_json::to_value(Scenario::builtin("paper_simple").unwrap()).unwrap();
    v["bounds"]["min"][1] = Value::from(1u64 << 40);
    let e = Scenario::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("field `bounds.min[1]`"), "{e}");
    let text = format!(
        "{} trailing",
        Scenario::builtin("paper_simple").unwrap().to_json()
    );
    assert!(Scenario::from_json(&text).is_err());
}
