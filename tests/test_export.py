"""URDF / MJCF export: loadable by yourdfpy and MuJoCo, with the core's forward kinematics
(1,000 random configurations, within 1e-6 mm), from the CLI and from Python."""

from __future__ import annotations

import subprocess

import mujoco
import numpy as np
import pytest
import sixaxis_avoid
import yourdfpy
from sixaxis_avoid import _core

N_CONFIGS = 1000
TOL_MM = 1e-6
#: The polyline's points after the base, as URDF links and as MJCF sites.
URDF_FRAMES = ["link1", "link2", "link3", "aux", "link4", "link5", "link6"]
MJCF_SITES = ["O1", "O2", "O3", "aux", "O4", "O5", "O6"]


def with_offsets(s: sixaxis_avoid.Scenario) -> sixaxis_avoid.Scenario:
    """The same arm written with non-zero joint offsets (beta_0 shifted to match) and joint
    limits: exercises the RotZ(offset) part of the joint origins and the ranges."""
    d = s.to_dict()
    offsets = [10.0, -20.0, 30.0, -40.0, 50.0, -60.0]
    for row, off in zip(d["arm"]["dh"], offsets):
        row["offset_deg"] = off
    d["arm"]["beta0_deg"] = [b - o for b, o in zip(d["arm"]["beta0_deg"], offsets)]
    d["arm"]["joint_limits_deg"] = [[-170.0, 170.0]] * 6
    d["name"] = "offsets"
    return sixaxis_avoid.Scenario(d)


@pytest.fixture(scope="module", params=["paper_simple", "offsets"])
def scenario(request, paper_simple):
    return paper_simple if request.param == "paper_simple" else with_offsets(paper_simple)


def configs(seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, size=(N_CONFIGS, 6))


def test_mujoco_fk_equals_ours(scenario):
    model = mujoco.MjModel.from_xml_string(sixaxis_avoid.export_scenario(scenario, "mjcf"))
    data = mujoco.MjData(model)
    assert model.nq == 6
    sites = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, n) for n in MJCF_SITES]
    terminal = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "terminal")
    arm = _core.Arm.from_scenario(scenario)
    worst_mm, worst_rot = 0.0, 0.0
    for q in configs():
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        ours = arm.points_mm(q)[1:]
        worst_mm = max(worst_mm, np.abs(data.site_xpos[sites] * 1000.0 - ours).max())
        _, rot = arm.fk(q)
        worst_rot = max(worst_rot, np.abs(data.site_xmat[terminal].reshape(3, 3) - rot).max())
    assert worst_mm < TOL_MM, worst_mm
    assert worst_rot < 1e-9, worst_rot


def test_yourdfpy_fk_equals_ours(scenario, tmp_path):
    path = tmp_path / "arm.urdf"
    sixaxis_avoid.export_scenario(scenario, "urdf", path)
    robot = yourdfpy.URDF.load(str(path), load_meshes=False)
    assert robot.actuated_joint_names == [f"joint{i}" for i in range(1, 7)]
    arm = _core.Arm.from_scenario(scenario)
    worst_mm, worst_rot = 0.0, 0.0
    for q in configs(1):
        robot.update_cfg(q)
        got = np.array([robot.get_transform(f, "base_link")[:3, 3] for f in URDF_FRAMES])
        worst_mm = max(worst_mm, np.abs(got * 1000.0 - arm.points_mm(q)[1:]).max())
        t = robot.get_transform("terminal", "base_link")
        _, rot = arm.fk(q)
        worst_rot = max(worst_rot, np.abs(t[:3, :3] - rot).max())
    assert worst_mm < TOL_MM, worst_mm
    assert worst_rot < 1e-9, worst_rot


def test_joint_ranges_follow_the_limits(paper_simple):
    m0 = mujoco.MjModel.from_xml_string(sixaxis_avoid.export_scenario(paper_simple, "mjcf"))
    np.testing.assert_allclose(m0.jnt_range, [[-np.pi, np.pi]] * 6)
    s = with_offsets(paper_simple)
    m1 = mujoco.MjModel.from_xml_string(sixaxis_avoid.export_scenario(s, "mjcf"))
    np.testing.assert_allclose(m1.jnt_range, np.radians([[-170.0, 170.0]] * 6))


def test_mjcf_scene_obstacles_target_and_radius(paper_simple):
    model = mujoco.MjModel.from_xml_string(sixaxis_avoid.export_scenario(paper_simple, "mjcf"))
    boxes = [g for g in range(model.ngeom) if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX]
    assert len(boxes) == len(paper_simple.obstacles)
    centres = sorted(
        tuple(np.round(model.geom_pos[g] * 1000.0 / paper_simple.cell_mm)) for g in boxes
    )
    assert centres == sorted(tuple(float(v) for v in c) for c in paper_simple.obstacles)
    np.testing.assert_allclose(model.geom_size[boxes], paper_simple.cell_mm / 2000.0)
    target = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "target")
    np.testing.assert_allclose(
        model.site_pos[target] * 1000.0, np.multiply(paper_simple.target, 100.0)
    )
    arm = [
        g for g in range(model.ngeom) if (mujoco.mj_id2name(model, 5, g) or "").startswith("seg")
    ]
    assert len(arm) == 7
    np.testing.assert_allclose(model.geom_size[arm, 0], 0.030)  # the documented default
    capsules = paper_simple.replace(
        planning={"clearance_model": {"kind": "capsules", "link_radius_mm": 45.0, "margin_mm": 5.0}}
    )
    m2 = mujoco.MjModel.from_xml_string(sixaxis_avoid.export_scenario(capsules, "mjcf"))
    np.testing.assert_allclose(m2.geom_size[arm, 0], 0.045)


def test_cli_export_matches_python(sixaxis_bin, tmp_path, paper_simple):
    for fmt in ("urdf", "mjcf"):
        out = tmp_path / f"scene.{fmt}"
        subprocess.run(
            [
                str(sixaxis_bin),
                "export",
                "--format",
                fmt,
                "--scenario",
                "paper_simple",
                "--out",
                str(out),
            ],
            check=True,
        )
        assert out.read_text() == sixaxis_avoid.export_scenario(paper_simple, fmt)
        stdout = subprocess.run(
            [str(sixaxis_bin), "export", "--format", fmt, "--scenario", "paper_simple"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        assert stdout == out.read_text()
    bad = subprocess.run(
        [str(sixaxis_bin), "export", "--format", "sdf", "--scenario", "paper_simple"],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "format" in bad.stderr and "sdf" in bad.stderr


def test_python_export_errors(tmp_path):
    with pytest.raises(sixaxis_avoid.InvalidArgumentError, match="format"):
        sixaxis_avoid.export_scenario("paper_simple", "sdf")
    with pytest.raises(sixaxis_avoid.SixAxisIOError):
        sixaxis_avoid.export_scenario("paper_simple", "urdf", tmp_path / "no" / "dir.urdf")
    assert list(tmp_path.iterdir()) == []
