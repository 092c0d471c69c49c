//! Fuzzing the request decoding (docs/SERVER.md "Reliability"): random bytes and mutated
//! valid `EnvironmentRequest`s are decoded and, when they decode, handled by a world as the
//! server would (settings checked, Step, Reset); nothing may panic. The counts are printed
//! (`cargo test -p sixaxis-server --release --test fuzz_decode -- --nocapture`);
//! `SIXAXIS_FUZZ_CASES` sets the cases per strategy (default 3000).

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use prost::Message;
use sixaxis_server::proto::environment::Request as Req;
use sixaxis_server::proto::tensor::{Int32Array, Int64Array, Payload, StringArray};
use sixaxis_server::proto::*;
use sixaxis_server::world::{reset_settings, World, WorldSettings};

#[derive(Default)]
struct Counts {
    cases: AtomicUsize,
    decoded: AtomicUsize,
    rejected_by_decoder: AtomicUsize,
    handled_ok: AtomicUsize,
    answered_with_status: AtomicUsize,
}

fn t_int(v: i64) -> Tensor {
    Tensor {
        payload: Some(Payload::Int64s(Int64Array { array: vec![v] })),
        shape: vec![],
    }
}

fn valid_requests() -> Vec<Vec<u8>> {
    let mut settings = BTreeMap::new();
    settings.insert("num_envs".to_string(), t_int(4));
    settings.insert("seed".to_string(), t_int(3));
    settings.insert(
        "obs_type".to_string(),
        Tensor {
            payload: Some(Payload::Strings(StringArray {
                array: vec!["goal".into()],
            })),
            shape: vec![],
        },
    );
    let mut actions = BTreeMap::new();
    actions.insert(
        1,
        Tensor {
            payload: Some(Payload::Int32s(Int32Array {
                array: vec![0, 1, 2, 3],
            })),
            shape: vec![4],
        },
    );
    let mut reset = BTreeMap::new();
    reset.insert("seed".to_string(), t_int(11));
    [
        Req::CreateWorld(CreateWorldRequest { settings }),
        Req::Step(StepRequest {
            actions,
            requested_observations: vec![1, 2, 3, 6, 7, 11],
        }),
        Req::Reset(ResetRequest { settings: reset }),
        Req::JoinWorld(JoinWorldRequest {
            world_name: "world-1-00".into(),
            settings: BTreeMap::new(),
        }),
    ]
    .into_iter()
    .map(|r| EnvironmentRequest { payload: Some(r) }.encode_to_vec())
    .collect()
}

fn handle(bytes: &[u8], world: &Mutex<World>, counts: &Counts) {
    counts.cases.fetch_add(1, Ordering::Relaxed);
    let req = match EnvironmentRequest::decode(bytes) {
        Ok(r) => r,
        Err(_) => {
            counts.rejected_by_decoder.fetch_add(1, Ordering::Relaxed);
            return;
        }
    };
    counts.decoded.fetch_add(1, Ordering::Relaxed);
    let mut w = world.lock().unwrap();
    let ok = match req.payload {
        Some(Req::CreateWorld(c)) => match WorldSettings::from_settings(&c.settings) {
            // Small worlds only: the point is the checks, not the allocation.
            Ok(s) if s.num_envs <= 64 && !s.arm_aware => World::new(&s).is_ok(),
            Ok(_) => true,
            Err(_) => false,
        },
        Some(Req::Step(s)) => w.step(&s).is_ok(),
        Some(Req::Reset(r)) => reset_settings(&r.settings).is_ok_and(|s| w.restart(&s).is_ok()),
        Some(Req::ResetWorld(r)) => reset_settings(&r.settings).is_ok(),
        Some(_) => true,
        None => false,
    };
    let c = if ok {
        &counts.handled_ok
    } else {
        &counts.answered_with_status
    };
    c.fetch_add(1, Ordering::Relaxed);
}

fn world() -> Mutex<World> {
    let mut settings = BTreeMap::new();
    settings.insert("num_envs".to_string(), t_int(4));
    settings.insert("random_target".to_string(), {
        Tensor {
            payload: Some(Payload::Bools(sixaxis_server::proto::tensor::BoolArray {
                array: vec![true],
            })),
            shape: vec![],
        }
    });
    let s = WorldSettings::from_settings(&settings).unwrap();
    let mut w = World::new(&s).unwrap();
    // Past the first Step, so Steps take actions.
    w.step(&StepRequest::default()).unwrap();
    Mutex::new(w)
}

fn cases() -> u32 {
    std::env::var("SIXAXIS_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000)
}

fn report(what: &str, c: &Counts) {
    eprintln!(
        "fuzz {what}: {} cases, {} rejected by the decoder, {} decoded ({} handled, {} answered with a Status)",
        c.cases.load(Ordering::Relaxed),
        c.rejected_by_decoder.load(Ordering::Relaxed),
        c.decoded.load(Ordering::Relaxed),
        c.handled_ok.load(Ordering::Relaxed),
        c.answered_with_status.load(Ordering::Relaxed),
    );
}

#[test]
fn random_bytes_never_panic() {
    let counts = Counts::default();
    let w = world();
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        ..Config::default()
    });
    runner
        .run(&proptest::collection::vec(any::<u8>(), 0..600), |bytes| {
            handle(&bytes, &w, &counts);
            Ok(())
        })
        .unwrap();
    report("random bytes", &counts);
    assert_eq!(counts.cases.load(Ordering::Relaxed), cases() as usize);
    assert!(counts.rejected_by_decoder.load(Ordering::Relaxed) > 0);
}

#[test]
fn mutated_valid_requests_never_panic() {
    let counts = Counts::default();
    let w = world();
    let valid = valid_requests();
    let strategy = (
        0..valid.len(),
        proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        any::<prop::sample::Index>(),
        any::<bool>(),
    );
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        ..Config::default()
    });
    runner
        .run(&strategy, |(k, edits, cut, truncate)| {
            let mut bytes = valid[k].clone();
            for (at, b) in edits {
                let i = at.index(bytes.len());
                bytes[i] = b;
            }
            if truncate {
                bytes.truncate(cut.index(bytes.len() + 1));
            }
            handle(&bytes, &w, &counts);
            Ok(())
        })
        .unwrap();
    report("mutated valid requests", &counts);
    assert!(counts.decoded.load(Ordering::Relaxed) > 0);
    assert!(counts.answered_with_status.load(Ordering::Relaxed) > 0);
}
