"""verify_plan: a plan replayed in MuJoCo, per move, against the core's own measures."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest
import sixaxis_avoid
from sixaxis_avoid import verify


def test_paper_paper_simple_plan_passes_eq11_but_its_centre_line_grazes_a_cube(paper_simple_plan):
    r = sixaxis_avoid.verify_plan(paper_simple_plan, "paper_simple")
    assert len(r.moves) == len(paper_simple_plan.path) - 1
    assert r.link_radius_mm == 30.0  # the export's default
    # Eq. 11 as the planner checked it: every step clears d_p.
    assert r.eq11_cells > paper_simple_plan.arm_safe_distance
    # The real geometry: the centre line comes within a millimetre of a cube, so the 30 mm
    # capsules overlap it and MuJoCo reports contacts.
    assert 0.0 < r.centre_line_mm < 1.0
    assert r.min_distance_mm == pytest.approx(r.centre_line_mm - 30.0)
    assert r.contacts > 0
    last = r.moves[-1]
    assert last.to_cell == tuple(paper_simple_plan.target) and last.contact_steps


def test_a_capsules_plan_has_no_contact_in_mujoco():
    s = sixaxis_avoid.Scenario("paper_simple").replace(
        planning={"clearance_model": {"kind": "capsules", "link_radius_mm": 10.0, "margin_mm": 0.0}}
    )
    p = sixaxis_avoid.plan(s, seed=0)
    assert p.success
    r = verify.verify_plan(p, s)
    assert r.link_radius_mm == 10.0
    # The core's capsules model (parry3d) accepted every step with a gap > 0; MuJoCo agrees.
    assert r.min_distance_mm > 0.0 and r.contacts == 0


def test_a_regridded_world_is_verified_against_its_boxes():
    """A physical world (the paper's cubes as boxes in mm, 50 mm cells): MuJoCo measures the
    boxes, and eq. 11 to the boxes' centres equals the planner's own figure."""
    s = sixaxis_avoid.Scenario("paper_simple").regrid(50)
    p = sixaxis_avoid.plan(s, seed=0, initial_q="distance")
    assert p.success and p.obstacles == []
    r = verify.verify_plan(p, s)
    assert r.eq11_cells == pytest.approx(p.min_centre_clearance_cells, abs=1e-9)
    assert r.eq11_cells > p.arm_safe_distance
    # The same cubes as at 100 mm: the centre line reaches a cube's surface, so the 30 mm
    # capsules overlap it.
    assert r.centre_line_mm < 1.0 and r.contacts > 0


def test_verify_uses_the_cores_interpolation_and_eq11(paper_simple_plan):
    """The motion replayed and eq. 11 are the core's: verify's eq. 11 is the planner's own
    figure to the bit, and the report keeps the figures it had when verify computed them
    in NumPy (to 1e-12; the interpolated angles differ from NumPy's by an ulp or so)."""
    from sixaxis_avoid import _core

    p = paper_simple_plan
    poses = np.asarray(p.poses_rad)
    t = p.interpolation_steps
    for k in range(len(poses) - 1):
        qs = verify.interpolate(poses[k], poses[k + 1], t)
        assert qs.shape == (t + 1, 6)
        np.testing.assert_array_equal(qs, _core.interpolate(poses[k], poses[k + 1], t))
    r = verify.verify_plan(p, "paper_simple")
    assert r.eq11_cells == p.min_centre_clearance_cells  # the planner's motion_clearance
    s = sixaxis_avoid.Scenario("paper_simple")
    for k, m in enumerate(r.moves):
        qs = _core.interpolate(poses[k], poses[k + 1], t)
        assert m.eq11_cells == float(np.min(_core.centres_clearance_cells(s, qs)))
    # The figures of the NumPy implementation this replaced (paper_simple, seed 0).
    assert r.eq11_cells == pytest.approx(0.7903176733467716, abs=1e-12)
    assert r.min_distance_mm == pytest.approx(-29.59997062275642, abs=1e-12)
    assert r.centre_line_mm == pytest.approx(0.40002937724358034, abs=1e-12)
    assert r.contacts == 154
    assert [round(m.eq11_cells, 9) for m in r.moves[:4]] == [0.967012065, 0.814713839, 1.0, 1.0]


def test_core_interpolation_and_eq11_check_their_inputs():
    from sixaxis_avoid import _core

    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="steps"):
        _core.interpolate(np.zeros(6), np.ones(6), 0)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="q1"):
        _core.interpolate(np.zeros(6), np.ones(5), 4)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="poses_rad"):
        _core.centres_clearance_cells("paper_simple", np.zeros((2, 5)))
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="cell_mm"):
        _core.centres_clearance_cells("paper_simple", np.zeros((1, 6)), -1.0)
    # No obstacle centres: infinitely far.
    empty = sixaxis_avoid.Scenario("paper_simple").replace(obstacles=[])
    assert _core.centres_clearance_cells(empty, np.zeros((2, 6))).tolist() == [np.inf] * 2


def test_interpolation_matches_the_planner():
    q0 = np.array([0.9 * np.pi, 0, 0, 0, 0, 0])
    q1 = np.array([-0.9 * np.pi, 0, 0, 0, 0, 1.0])
    qs = verify.interpolate(q0, q1, 4)
    np.testing.assert_allclose(qs[0], q0)
    np.testing.assert_allclose(qs[-1], q1)
    np.testing.assert_allclose(np.diff(np.unwrap(qs[:, 0])), 0.2 * np.pi / 4)  # across +-pi


def test_cli_plan_json_gives_the_same_report(paper_simple_plan, sixaxis_bin, tmp_path):
    plan_json = tmp_path / "plan.json"
    subprocess.run(
        [
            str(sixaxis_bin),
            "plan",
            "--scenario",
            "paper_simple",
            "--seed",
            "0",
            "--out",
            str(plan_json),
        ],
        check=True,
    )
    out = tmp_path / "report.json"
    verify.main(["--plan", str(plan_json), "--scenario", "paper_simple", "--json", str(out)])
    from_cli = json.loads(out.read_text())
    direct = verify.verify_plan(paper_simple_plan, "paper_simple").to_dict()
    assert from_cli["min_distance_mm"] == pytest.approx(direct["min_distance_mm"], abs=1e-9)
    assert [m["contact_steps"] for m in from_cli["moves"]] == [
        m["contact_steps"] for m in direct["moves"]
    ]


def test_bad_plans_are_named():
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="plan"):
        verify.verify_plan(42)
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="plan"):
        verify.verify_plan({"poses_rad": [], "obstacles": [], "path": []})
