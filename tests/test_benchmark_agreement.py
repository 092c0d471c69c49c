"""The JAX-vs-SB3 agreement study's statistics and its mapping of hyperparameters."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("optuna")  # the benchmark extra, as the other benchmark tests

from sixaxis_avoid.benchmark import agreement


def test_identical_samples_agree_and_disjoint_ones_do_not():
    same = np.array([[0.0, 1.0], [0.0, 1.0], [1.0, 1.0], [0.0, 0.0], [1.0, 1.0]])
    r = agreement.summarise(same, same.copy())
    assert r["agree"] and r["final"]["overlap"] and r["auc"]["overlap"]
    assert r["final"]["permutation_p"] == pytest.approx(1.0)
    lo = np.zeros((5, 3))
    hi = np.ones((5, 3))
    r = agreement.summarise(lo, hi)
    assert not r["agree"]
    assert r["final"]["jax"]["ci"] == [0.0, 0.0] and r["final"]["sb3"]["ci"] == [1.0, 1.0]
    # 5 vs 5 with all ones against all zeros: 2 of the 252 splits are as extreme.
    assert r["final"]["permutation_p"] == pytest.approx(2 / 252)


def test_on_points_takes_the_first_evaluation_at_or_past_each_point():
    curve = [(2560, 0.0), (5120, 0.5), (7680, 1.0)]
    assert agreement.on_points(curve, [2560, 5120, 7680]) == [0.0, 0.5, 1.0]
    assert agreement.on_points([(2564, 0.2), (5128, 0.4)], [2560, 5120]) == [0.2, 0.4]
    with pytest.raises(RuntimeError, match="7680"):
        agreement.on_points(curve[:2], [7680])


def test_sb3_values_are_the_jax_values_less_sb3s_own_activation():
    pytest.importorskip("jax")
    from sixaxis_avoid.benchmark import jax_learners

    j = agreement.jax_args(
        agreement.parse_args(["--tasks", "paper_simple", "--set", "learning_rate=0.001"]),
        "paper_simple",
    )
    assert j.budget == 30_000 and j.evaluations == 12 and j.set == ["learning_rate=0.001"]
    values = jax_learners.check_values("ppo", jax_learners.parse_sets(j.set))
    v = agreement.sb3_values("ppo", values)
    assert v["learning_rate"] == 0.001 and "activation" not in v
    assert {k: x for k, x in values.items() if k != "activation"} == v
    with pytest.raises(ValueError, match="activation"):
        agreement.sb3_values("dqn", {**values, "activation": "tanh"})
    assert agreement.sb3_values("ppo", values, "rejax") == {**v, "implementation": "rejax"}
    assert agreement.parse_args(["--sb3-implementation", "rejax"]).sb3_implementation == "rejax"


def test_the_section_is_written_from_the_result_files_and_keeps_the_page(tmp_path):
    flags = vars(agreement.parse_args(["--tasks", "t1", "--seeds", "2"])) | {"out": "x.json"}
    flags.pop("from_json")
    flags["markdown"] = None
    jax_s = np.array([[0.0, 1.0], [0.0, 0.0]])
    sb3_s = np.array([[1.0, 1.0], [1.0, 1.0]])
    result = {
        "flags": flags,
        "machine": "test cpu",
        "tasks": {
            "t1": {
                "jax": {"spl": jax_s.tolist(), "env_steps_per_s": 1000.0},
                "sb3": {"spl": sb3_s.tolist(), "env_steps_per_s": 100.0},
                "agreement": agreement.summarise(jax_s, sb3_s),
            }
        },
    }
    src = tmp_path / "r.json"
    src.write_text(__import__("json").dumps(result))
    page = tmp_path / "page.md"
    page.write_text("# Page\n\nkept text\n")
    agreement.main(["--from-json", str(src), "--markdown", str(page)])
    body = page.read_text()
    assert body.startswith("# Page\n\nkept text\n")
    row = next(line for line in body.splitlines() if line.startswith("| ppo | t1 | 30,000 |"))
    assert "| 0.50 [0.00, 1.00] | 1.00 [1.00, 1.00] |" in row and row.endswith("| **no** |")
    assert "--tasks t1 --seeds 2 --budget 30000 --evaluations 12" in body and "--out x.json" in body
    assert "PPO, value loss" in body and "DQN, loss" not in body
    assert "JAX 1,000 env steps/s" in body and "SB3 100" in body
    # Re-writing replaces the section rather than appending a second one.
    agreement.main(["--from-json", str(src), "--markdown", str(page)])
    assert page.read_text().count("jax-sb3-agreement:begin") == 1


def test_ppo_ablation_section_names_the_cause_from_the_committed_figures():
    """The v2 PPO ablation (scripts/implementation_ablation.py) renders its table, the gradient-norm
    reading of the cause with the file's own figures, and the commands that made it."""
    import json
    from pathlib import Path

    path = "docs/results/agreement/ppo-v2-ablation.json"
    ab = json.loads((Path(__file__).resolve().parents[1] / path).read_text())
    text = "\n".join(agreement.ablation_markdown(ab, path))
    for name, row in ab["variants"].items():
        assert f"| {name} | {row['what']} | {row['mean_spl']:.3f} |" in text
        assert row["command"] in text
    sb3 = ab["gradnorms"]["sb3"]["median"]["first third"]
    assert f"scales both by {sb3['clip_factor']:.4f}" in text
    assert (
        sb3["actor_rms_after_clip"]
        < 1e-5
        < ab["gradnorms"]["vfclip"]["median"]["last third"]["actor_rms_after_clip"]
    )
    assert "implementation: rejax" in text


def test_merge_v2_adds_a_new_learners_runs_and_replaces_a_re_run(tmp_path):
    """scripts/implementation_ablation.py merge-v2: a learner's runs made outside the study
    come in with their command, wall time and count; a re-run at the same budget replaces the
    old files and command but keeps other learners' and other budgets' commands."""
    import importlib.util
    import json
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "implementation_ablation",
        Path(__file__).resolve().parents[1] / "scripts" / "implementation_ablation.py",
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)

    def study(d, learners, commands, runs, wall):
        (d / "runs").mkdir(parents=True)
        for name, w in runs:
            (d / "runs" / name).write_text(json.dumps({"timing": {"run_wall_time_s": w}}))
        man = {"command": commands[-1], "commands": commands, "learners": learners,
               "runs": len(runs), "ran_now": len(runs), "skipped_now": 0,
               "wall_time_s_now": wall, "wall_time_s_total": wall, "failures": [],
               "date": "d", "machine": "m", "versions": {}, "load_average": [0, 0, 0]}  # fmt: skip
        (d / "study.json").write_text(json.dumps(man))

    v2, new = tmp_path / "v2", tmp_path / "new"
    c = "run --learners {} --budgets {} --out-dir {}"
    old = [("t__jax_dqn__s0__b30000.json", 5.0), ("t__jax_dqn__s0__b100000.json", 7.0)]
    study(v2, ["jax_dqn"], [c.format("jax_dqn", b, v2) for b in (30000, 100000)], old, 12.0)
    study(new, ["dqn"], [c.format("dqn", 30000, new)], [("t__dqn__s0__b30000.json", 3.0)], 4.0)
    out = mod.merge_v2("dqn", new, v2)
    man = json.loads((v2 / "study.json").read_text())
    assert out["replaced"] == 1 and man["runs"] == 3 and man["learners"] == ["jax_dqn", "dqn"]
    assert man["wall_time_s_total"] == 16.0 and man["commands"][-1] == c.format("dqn", 30000, v2)
    # A re-run of jax_dqn at 30k replaces its 30k runs and command only.
    new2 = tmp_path / "new2"
    study(new2, ["jax_dqn"], [c.format("jax_dqn", 30000, new2)],
          [("t__jax_dqn__s0__b30000.json", 2.0)], 2.5)  # fmt: skip
    mod.merge_v2("jax_dqn", new2, v2)
    man = json.loads((v2 / "study.json").read_text())
    assert man["runs"] == 3 and man["wall_time_s_total"] == 16.0 - 5.0 + 2.5
    assert man["commands"] == [
        c.format("jax_dqn", 100000, v2), c.format("dqn", 30000, v2), c.format("jax_dqn", 30000, v2)
    ]  # fmt: skip
    # The replaced files are kept beside the study, with what made and replaced them.
    kept = tmp_path / "v2-replaced" / "jax_dqn-30000"
    (f,) = (kept / "runs").iterdir()
    assert f.name == "t__jax_dqn__s0__b30000.json"
    assert json.loads(f.read_text())["timing"]["run_wall_time_s"] == 5.0  # the old one
    about = json.loads((kept / "replaced.json").read_text())
    assert (about["learner"], about["budgets"], about["runs"]) == ("jax_dqn", [30000], 1)
    assert about["commands"] == [c.format("jax_dqn", 30000, v2)]
    assert about["replaced_by"] == c.format("jax_dqn", 30000, v2)
    assert not (tmp_path / "v2-replaced" / "dqn-30000").exists()  # dqn's runs were added
    from sixaxis_avoid.benchmark.report_pending import replaced_sets

    (kept_set,) = replaced_sets(v2)  # what the page's check of JAX against SB3 reads
    assert kept_set["dir"] == str(kept) and kept_set["learner"] == "jax_dqn"
    assert [r["timing"]["run_wall_time_s"] for r in kept_set["runs"]] == [5.0]
    (new2 / "runs" / "u__jax_dqn__s0__b30000.json").write_text("{}")
    with pytest.raises(SystemExit, match="not the same set"):
        mod.merge_v2("jax_dqn", new2, v2)
    # More seeds of dqn at 30k (no file in common): added, every earlier command kept.
    new3 = tmp_path / "new3"
    # A path inside the checkout (an absolute --hyperparams) is written relative to it.
    hp = " --hyperparams {}python/sixaxis_avoid/benchmark/hyperparams/v2.json"
    study(new3, ["dqn"], [c.format("dqn", 30000, new3) + hp.format(f"{mod.ROOT}/")],
          [("t__dqn__s5__b30000.json", 1.5)], 2.0)  # fmt: skip
    before = man["commands"]
    mod.merge_v2("dqn", new3, v2)
    man = json.loads((v2 / "study.json").read_text())
    assert man["runs"] == 4 and man["wall_time_s_total"] == 16.0 - 5.0 + 2.5 + 2.0
    assert man["commands"] == [*before, c.format("dqn", 30000, v2) + hp.format("")]
    assert (v2 / "runs" / "t__dqn__s0__b30000.json").exists()
    # A directory filled by a command that was stopped and then resumed: the wall time of
    # both (wall_time_s_total) comes in, not only the last command's; while its last
    # command is stopped (finished: false) it is refused, and nothing in the study changes.
    new4 = tmp_path / "new4"
    study(new4, ["dqn"], [c.format("dqn", 30000, new4)],
          [("t__dqn__s6__b30000.json", 1.0)], 3.0)  # fmt: skip
    resumed = json.loads((new4 / "study.json").read_text())
    (new4 / "study.json").write_text(json.dumps({**resumed, "finished": False}))
    with pytest.raises(SystemExit, match="was stopped"):
        mod.merge_v2("dqn", new4, v2)
    assert json.loads((v2 / "study.json").read_text()) == man
    # Likewise a command that ended with failed runs (they have no file yet).
    failed = {**resumed, "finished": True, "failures": [["t__dqn__s7__b30000", "raylet died"]]}
    (new4 / "study.json").write_text(json.dumps(failed))
    with pytest.raises(SystemExit, match="left 1 runs failed"):
        mod.merge_v2("dqn", new4, v2)
    assert json.loads((v2 / "study.json").read_text()) == man
    resumed.update(finished=True, wall_time_s_now=1.0, wall_time_s_total=3.0)
    (new4 / "study.json").write_text(json.dumps(resumed))
    mod.merge_v2("dqn", new4, v2)
    man = json.loads((v2 / "study.json").read_text())
    assert man["runs"] == 5 and man["wall_time_s_total"] == 16.0 - 5.0 + 2.5 + 2.0 + 3.0


def test_dqn_ablation_section_reads_the_cause_from_the_committed_figures():
    """The v2 DQN ablation (scripts/implementation_ablation.py --algo dqn) renders each
    variant's row and command, and its reading of the cause from the file's own counts: the
    squared loss alone closes the gap that every other rejax setting leaves open."""
    import json
    from pathlib import Path

    path = "docs/results/agreement/dqn-v2-ablation.json"
    ab = json.loads((Path(__file__).resolve().parents[1] / path).read_text())
    text = "\n".join(agreement.ablation_markdown(ab, path))
    assert "### Why SB3 DQN failed with jax_dqn's values" in text
    for name, row in ab["variants"].items():
        assert f"| {name} | {row['what']} | {row['mean_spl']:.3f} |" in text
        assert row["command"] in text
    sq, hu = ab["variants"]["squared"], ab["variants"]["huber"]
    assert f"in {sq['successes']}/{sq['runs']} runs" in text
    assert f"in {hu['successes']}/{hu['runs']}" in text
    assert sq["successes"] > hu["successes"]  # the reading the section gives


def test_replay_draw_check_pairs_runs_and_refuses_other_differences(tmp_path):
    """scripts/replay_draw_check.py summary: jax_dqn's runs with rejax's draw and with SB3's,
    paired by task and seed; means, Wilson counts and the section's verdict come from the
    files; run sets that differ in anything but the draw are refused."""
    import importlib.util
    import json
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "replay_draw_check",
        Path(__file__).resolve().parents[1] / "scripts" / "replay_draw_check.py",
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    hp = {"learning_rate": 0.002, "gamma": 0.98}

    def runs(d, extra, scores):
        (d / "runs").mkdir(parents=True)
        for (task, seed), s in scores.items():
            r = {"spec": {"task": {"id": task}, "seed": seed, "hyperparams": {**hp, **extra}},
                 "result": {"score": s, "success": s > 0}}  # fmt: skip
            (d / "runs" / f"{task}__jax_dqn__s{seed}__b30000.json").write_text(json.dumps(r))

    keys = [(t, s) for t in ("a", "b", "c") for s in range(4)]
    base, var = tmp_path / "base", tmp_path / "var"
    runs(base, {}, {k: 1.0 if k[0] != "c" else 0.0 for k in keys})
    runs(
        var, {"replay_sample": "with_replacement"}, {k: 1.0 if k != ("c", 0) else 0.0 for k in keys}
    )
    out = mod.summary(base, var)
    wo, wi = out["draws"]["without_replacement"], out["draws"]["with_replacement"]
    assert out["tasks"] == ["a", "b", "c"] and out["seeds"] == [0, 1, 2, 3]
    assert wo["successes"] == 8 and wi["successes"] == 11 and wo["runs"] == 12
    assert wo["mean_spl"] == pytest.approx(8 / 12) and wi["mean_spl"] == pytest.approx(11 / 12)
    assert wo["per_task_mean_spl"]["c"] == 0.0 and wi["per_task_mean_spl"]["c"] == 0.75
    text = mod.markdown(out)
    assert "8/12" in text and "11/12" in text and "c (0.00 against 0.75)" in text
    # One more difference than the draw: refused.
    other = tmp_path / "other"
    runs(other, {"replay_sample": "with_replacement", "gamma": 0.9}, dict.fromkeys(keys, 1.0))
    with pytest.raises(SystemExit, match="more than the draw"):
        mod.summary(base, other)
    # The section is written between its markers, and rewritten in place.
    page = tmp_path / "page.md"
    page.write_text("# P\n\ntext\n")
    mod.write_section(page, "one")
    mod.write_section(page, "two")
    body = page.read_text()
    assert body.count("jax-dqn-replay-draw:begin") == 1 and "two" in body and "one" not in body
