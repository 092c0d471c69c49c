//! f32 Q-values.

use super::*;
use crate::files::is_invalid_data;

fn f32_options(sc: &Scenario, episodes: u32, seed: u64) -> Learning {
    let mut o = Learning::from_scenario(sc);
    o.episodes = episodes;
    o.epsilon_decay_episodes = episodes - episodes / 100;
    o.seed = seed;
    o.q_precision = QPrecision::F32;
    o
}

#[test]
fn f32_learner_matches_plain_reference_bit_for_bit() {
    // The same learner with its values stored as f32: the plain reference learner
    // (`q_update`, which computes in f64 and stores rounded) on an f32 table gives the same
    // table, bit for bit, and the same episodes.
    for (name, seed, assist, episodes) in [
        ("paper_simple", 7, Assist::on(), 600),
        ("paper_simple", 8, Assist::off(), 600),
        ("replan_clutter", 10, only_distance(), 300),
    ] {
        let sc = scenario(name);
        let w = GridWorld::new(&sc).unwrap();
        let mut o = f32_options(&sc, episodes, seed);
        o.set_assist(assist);
        o.max_steps_per_episode = 300;
        let r = train(&w, &o, None, None).unwrap();
        assert_eq!(r.q.precision(), QPrecision::F32);
        let q0 = QTable::zeros_with(w.num_states(), QPrecision::F32);
        let (q, steps) = reference_train(&w, &o, Some(q0));
        assert_eq!(r.q, q, "{name} seed {seed}");
        assert_eq!(r.steps_per_episode, steps);
        assert_eq!(r.path, greedy_path(&w, &r.q, o.max_steps_per_episode));
    }
}

#[test]
fn f32_training_is_deterministic_and_takes_half_the_bytes() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let o = f32_options(&sc, 2000, 0);
    let a = train(&w, &o, None, None).unwrap();
    let b = train(&w, &o, None, None).unwrap();
    assert_eq!(a.q, b.q);
    assert_eq!(a.path, b.path);
    assert_eq!(a.steps_per_episode, b.steps_per_episode);
    assert_eq!(a.converged_episode, b.converged_episode);
    // Every value is an f32 (read back as f64 exactly).
    let v32 = a.q.values_f32().unwrap();
    assert!(a.q.values_f64().is_none());
    assert!(a
        .q
        .values()
        .iter()
        .zip(v32)
        .all(|(x, y)| x.to_bits() == (*y as f64).to_bits()));
    assert!(v32.iter().filter(|v| **v != 0.0).count() > 100);
    let c = train(&w, &Learning { seed: 1, ..o }, None, None).unwrap();
    assert_ne!(a.q, c.q);
    // 24 bytes of Q-values per state against 48; the default stays f64.
    let f64_run = train(
        &w,
        &Learning {
            q_precision: QPrecision::F64,
            ..o
        },
        None,
        None,
    )
    .unwrap();
    assert_eq!(
        (a.q.bytes_per_state(), f64_run.q.bytes_per_state()),
        (24, 48)
    );
    assert_eq!(Learning::from_scenario(&sc).q_precision, QPrecision::F64);
    // The f64 learner asked for explicitly is the default learner, bit for bit.
    let mut default = Learning::from_scenario(&sc);
    default.episodes = 2000;
    default.epsilon_decay_episodes = 1980;
    assert_eq!(train(&w, &default, None, None).unwrap().q, f64_run.q);
}

#[test]
fn f32_qtable_file_round_trip_is_exact() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = train(&w, &f32_options(&sc, 500, 3), None, None).unwrap().q;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q32.qtable");
    q.save(&path, &w).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header_end = bytes.iter().skip(17).position(|&b| b == b'\n').unwrap() + 18;
    let header = std::str::from_utf8(&bytes[17..header_end]).unwrap();
    assert!(header.contains("\"values\":\"f32\""), "{header}");
    assert!(
        header.contains("\"layout\":\"f32 little-endian"),
        "{header}"
    );
    assert_eq!(bytes.len() - header_end, w.num_states() * 6 * 4);
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!(back.precision(), QPrecision::F32);
    assert_eq!(back, q);
    let bits = |t: &QTable| -> Vec<u32> {
        t.values_f32()
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&back), bits(&q));
    // An f64 table says so too, and is twice the size.
    let q64 = trained(&w, &sc, 50, 0);
    let p64 = dir.path().join("q64.qtable");
    q64.save(&p64, &w).unwrap();
    let b64 = std::fs::read(&p64).unwrap();
    assert!(String::from_utf8_lossy(&b64).contains("\"values\":\"f64\""));
    assert_eq!(QTable::load(&p64, &w).unwrap().precision(), QPrecision::F64);
}

#[test]
fn qtable_file_without_a_value_type_reads_as_f64() {
    // Files written before f32 tables existed have no `values` field in the header.
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 200, 2);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let text = std::fs::read(&path).unwrap();
    let field = b"\"values\":\"f64\",";
    let at = text.windows(field.len()).position(|x| x == field).unwrap();
    let mut old = text[..at].to_vec();
    old.extend_from_slice(&text[at + field.len()..]);
    std::fs::write(&path, &old).unwrap();
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!((back.precision(), &back), (QPrecision::F64, &q));
    // A header claiming f32 over f64 values, or naming another type, is refused.
    for claim in [&b"\"values\":\"f32\","[..], b"\"values\":\"f16\","] {
        let mut lie = text[..at].to_vec();
        lie.extend_from_slice(claim);
        lie.extend_from_slice(&text[at + field.len()..]);
        std::fs::write(&path, &lie).unwrap();
        assert!(is_invalid_data(QTable::load(&path, &w)));
    }
}

#[test]
fn a_table_of_the_other_precision_is_converted_for_training() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut o = f32_options(&sc, 300, 4);
    let q64 = trained(&w, &sc, 400, 1);
    // f64 table, f32 run: rounded to the nearest f32 first.
    let a = train(&w, &o, Some(q64.clone()), None).unwrap();
    let rounded = q64.clone().into_precision(QPrecision::F32).unwrap();
    assert!(rounded
        .values()
        .iter()
        .zip(q64.values())
        .all(|(r, v)| *r == (v as f32) as f64));
    let b = train(&w, &o, Some(rounded.clone()), None).unwrap();
    assert_eq!(a.q.precision(), QPrecision::F32);
    assert_eq!(a.q, b.q);
    // f32 table, f64 run: exact.
    o.q_precision = QPrecision::F64;
    let widened = rounded.clone().into_precision(QPrecision::F64).unwrap();
    assert_eq!(widened.values(), rounded.values());
    let c = train(&w, &o, Some(rounded), None).unwrap();
    let d = train(&w, &o, Some(widened), None).unwrap();
    assert_eq!(c.q.precision(), QPrecision::F64);
    assert_eq!(c.q, d.q);
    // A value beyond the f32 range cannot be converted: an error naming it.
    let mut big = QTable::zeros(w.num_states());
    big.set(5, 2, 1e39);
    o.q_precision = QPrecision::F32;
    let e = train(&w, &o, Some(big), None).unwrap_err().to_string();
    assert!(
        e.contains("`q_precision` = f32") && e.contains("(state 5, action 2) does not fit in f32"),
        "{e}"
    );
}

#[test]
fn f32_q_update_stores_the_rounded_f64_update() {
    let sc = corridor();
    let w = GridWorld::new(&sc).unwrap();
    let s0 = w.start();
    let mut q = QTable::zeros_with(w.num_states(), QPrecision::F32);
    q.set(s0, PX, 0.1);
    assert_eq!(q.get(s0, PX), 0.1f32 as f64);
    let t = w.step(s0, PX, None, Assist::on());
    let expect = (0.1f32 as f64) + 0.05 * (t.reward + 0.9 * 0.0 - (0.1f32 as f64));
    assert_eq!(
        q_update(&mut q, s0, PX, &t, 0.05, 0.9),
        expect as f32 as f64
    );
    assert_eq!(q.row(s0)[PX], expect as f32 as f64);
}
