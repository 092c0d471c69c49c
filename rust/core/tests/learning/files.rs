//! Q-table files and resuming from them.

use super::*;

#[test]
fn qtable_save_load_roundtrip_is_exact() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 500, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let back = QTable::load(&path, &w).unwrap();
    assert_eq!(back, q);
    assert!(back
        .values()
        .iter()
        .zip(q.values())
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    // Overwriting works and leaves only the file.
    let q2 = trained(&w, &sc, 50, 1);
    q2.save(&path, &w).unwrap();
    assert_eq!(QTable::load(&path, &w).unwrap(), q2);
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
    let text = std::fs::read(&path).unwrap();
    assert!(text.starts_with(b"SIXAXIS-QTABLE 1\n{"));
}

#[test]
fn qtable_load_onto_another_world_is_a_mismatch() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 100, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();

    // paper_complex: same cells blocked (d_s 0.95 vs 0.96 < 1), same bounds and target.
    let complex = GridWorld::new(&scenario("paper_complex")).unwrap();
    assert_eq!(QTable::load(&path, &complex).unwrap(), q);

    let mismatch = |w: &GridWorld| match QTable::load(&path, w) {
        Err(Error::QTableMismatch(msg)) => msg,
        other => panic!("expected a mismatch, got {other:?}"),
    };
    let shelf = GridWorld::new(&scenario("replan_clutter")).unwrap();
    let msg = mismatch(&shelf);
    assert!(msg.contains("obstacles differ"), "{msg}");
    let extra = GridWorld::with_extra_obstacles(&sc, &[[0, 0, 0]]).unwrap();
    mismatch(&extra);
    let mut moved = w.clone();
    moved.set_target([2, 2, 2]).unwrap();
    assert!(mismatch(&moved).contains("target"));
    let mut small = sc.clone();
    small.bounds.max = [3, 5, 4];
    let msg = mismatch(&GridWorld::new(&small).unwrap());
    assert!(msg.contains("bounds"), "{msg}");
    // A table of the wrong size cannot be saved for this world either.
    assert!(matches!(
        QTable::zeros(5).save(&dir.path().join("x"), &w),
        Err(Error::QTableMismatch(_))
    ));
    // The start is recorded but does not have to match.
    let mut moved_start = w.clone();
    moved_start.set_start([0, -2, 3]).unwrap();
    assert_eq!(QTable::load(&path, &moved_start).unwrap(), q);
}

/// Whether loading gave an I/O error of kind `InvalidData` (a bad file, not a missing one).
pub(crate) fn is_invalid_data(r: sixaxis_core::Result<QTable>) -> bool {
    matches!(r, Err(Error::Io { ref source, .. }) if source.kind() == std::io::ErrorKind::InvalidData)
}

#[test]
fn corrupt_or_foreign_files_are_io_errors() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 50, 0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    q.save(&path, &w).unwrap();
    let good = std::fs::read(&path).unwrap();
    // Truncated.
    std::fs::write(&path, &good[..good.len() - 8]).unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // A flipped bit in the values.
    let mut bad = good.clone();
    let last = bad.len() - 1;
    bad[last] ^= 1;
    std::fs::write(&path, &bad).unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // Not a Q-table.
    std::fs::write(&path, b"{\"hello\": 1}").unwrap();
    assert!(is_invalid_data(QTable::load(&path, &w)));
    // Missing.
    assert!(matches!(
        QTable::load(&dir.path().join("missing"), &w),
        Err(Error::Io { .. })
    ));
}

#[test]
fn qtable_save_is_atomic_and_leaves_nothing_on_error() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let q = trained(&w, &sc, 50, 0);
    let dir = tempfile::tempdir().unwrap();
    // The destination is a directory: the final rename fails after the temporary file
    // was written; the temporary file must be gone.
    let target = dir.path().join("occupied");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("keep"), b"x").unwrap();
    let err = q.save(&target, &w).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["occupied".to_string()]);
    // A missing directory: an error, nothing created.
    let err = q
        .save(&dir.path().join("no/such/dir/q.qtable"), &w)
        .unwrap_err();
    assert!(matches!(err, Error::Io { .. }));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // An existing file is replaced whole, never left half-written: after a failed save
    // onto a good file the good file is intact.
    let good = dir.path().join("good.qtable");
    q.save(&good, &w).unwrap();
    assert!(QTable::zeros(3).save(&good, &w).is_err());
    assert_eq!(QTable::load(&good, &w).unwrap(), q);
}

// ---------------------------------------------------------------- resume

#[test]
fn resume_from_saved_table_is_deterministic() {
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut first = Learning::from_scenario(&sc);
    first.episodes = 1500;
    first.epsilon_decay_episodes = 3000;
    first.seed = 11;
    let r1 = train(&w, &first, None, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.qtable");
    r1.q.save(&path, &w).unwrap();

    // The second run: its own seed and its own epsilon schedule, counted from 0.
    let mut second = first;
    second.seed = 12;
    second.episodes = 1000;
    second.epsilon_start = 0.05;
    second.epsilon_decay_episodes = 900;
    let a = train(&w, &second, Some(QTable::load(&path, &w).unwrap()), None).unwrap();
    let b = train(&w, &second, Some(QTable::load(&path, &w).unwrap()), None).unwrap();
    let c = train(&w, &second, Some(r1.q.clone()), None).unwrap();
    assert_eq!(a.q, b.q);
    assert_eq!(a.q, c.q);
    assert_eq!(a.steps_per_episode, b.steps_per_episode);
    assert_eq!(a.path, b.path);
    assert_eq!(a.converged_episode, b.converged_episode);
    // Equal to the plain reference learner started from the same table.
    let (q_ref, steps_ref) = reference_train(&w, &second, Some(r1.q.clone()));
    assert_eq!(a.q, q_ref);
    assert_eq!(a.steps_per_episode, steps_ref);
    // Another seed for the second run gives another run.
    second.seed = 13;
    let d = train(&w, &second, Some(r1.q.clone()), None).unwrap();
    assert_ne!(a.steps_per_episode, d.steps_per_episode);
    // Resuming changed the table (it learned).
    assert_ne!(a.q, r1.q);
    if let Some(p) = &a.path {
        check_path(&w, p);
    }
}

#[test]
fn resume_continues_learning_to_a_path() {
    // 5000 episodes, then 5000 more from that table with the rest of the paper's schedule
    // (epsilon from 0.05 down to 0 over 4900 episodes): the path is learned.
    let sc = scenario("paper_simple");
    let w = GridWorld::new(&sc).unwrap();
    let mut first = Learning::from_scenario(&sc);
    first.episodes = 5000;
    let r1 = train(&w, &first, None, None).unwrap();
    let mut second = first;
    second.seed = 1;
    second.epsilon_start = first.epsilon(5000);
    second.epsilon_decay_episodes = 4900;
    let r2 = train(&w, &second, Some(r1.q), None).unwrap();
    let p = r2.path.expect("resumed run reaches the target");
    check_path(&w, &p);
    println!(
        "paper_simple 5000 + 5000 episodes: path {} steps, converged at episode {:?} of the second run",
        p.len() - 1,
        r2.converged_episode
    );
}
