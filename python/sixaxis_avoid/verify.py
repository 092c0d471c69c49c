"""Plans checked in MuJoCo: replay a plan's interpolated motion and measure the real geometry.

:func:`verify_plan` exports the scenario as MJCF (``sixaxis_avoid.export_scenario``), loads
it in MuJoCo, and replays the plan kinematically: for every move between two consecutive
poses, each of the plan's ``interpolation_steps`` joint-space steps (each joint along its
shortest angular difference, as the planner checks them) is set as ``qpos``, ``mj_forward``
runs, and ``mj_geomDistance`` measures every arm capsule against every obstacle box. It
reports per move the smallest capsule-box distance (mm, negative when they overlap), the
same for the arm's centre line (capsule distance + radius), eq. 11's smallest distance from
the polyline to an obstacle centre (cells), and the steps at which MuJoCo found a contact.
The interpolation and eq. 11 are the core's (``_core.interpolate``,
``_core.centres_clearance_cells``): the code the planner checks motions with.

Command line (needs the ``mujoco`` extra)::

    python -m sixaxis_avoid.verify --scenario paper_simple --seed 0
    python -m sixaxis_avoid.verify --plan plan.json --scenario paper_simple --json out.json
    python -m sixaxis_avoid.verify --table          # every shipped scenario, both models
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from sixaxis_avoid import _core
from sixaxis_avoid._checks import invalid
from sixaxis_avoid._deps import require

#: The capsules model of the table: links of this radius must not touch a cube (margin 0).
TABLE_LINK_RADIUS_MM = 30.0


@dataclass
class MoveCheck:
    """One move of a plan, from pose ``index`` to pose ``index + 1``."""

    index: int
    from_cell: tuple[int, int, int]
    to_cell: tuple[int, int, int]
    #: Smallest capsule-box distance over the move's steps, mm (< 0: overlap).
    min_distance_mm: float
    #: Smallest distance from the arm's centre line to a box, mm (< 0: the line enters it).
    centre_line_mm: float
    #: Eq. 11: smallest distance from the polyline to an obstacle centre, cells.
    eq11_cells: float
    #: Interpolation steps (0..=t) at which MuJoCo reported an arm-obstacle contact.
    contact_steps: list[int] = field(default_factory=list)
    #: Arm geom and obstacle geom of the smallest distance.
    closest: tuple[str, str] = ("", "")


@dataclass
class VerifyReport:
    """MuJoCo's view of a plan."""

    link_radius_mm: float
    interpolation_steps: int
    moves: list[MoveCheck]

    @property
    def min_distance_mm(self) -> float:
        return min((m.min_distance_mm for m in self.moves), default=float("inf"))

    @property
    def centre_line_mm(self) -> float:
        return min((m.centre_line_mm for m in self.moves), default=float("inf"))

    @property
    def eq11_cells(self) -> float:
        return min((m.eq11_cells for m in self.moves), default=float("inf"))

    @property
    def contacts(self) -> int:
        """Number of replayed steps with a contact."""
        return sum(len(m.contact_steps) for m in self.moves)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(
            min_distance_mm=self.min_distance_mm,
            centre_line_mm=self.centre_line_mm,
            eq11_cells=self.eq11_cells,
            contacts=self.contacts,
        )
        return d


def interpolate(q0: np.ndarray, q1: np.ndarray, steps: int) -> np.ndarray:
    """``steps + 1`` poses from ``q0`` to ``q1`` (radians), each joint along its shortest
    angular difference: the poses at which the core's planner checks the move
    (``_core.interpolate``); shape ``(steps + 1, 6)``."""
    return _core.interpolate(q0, q1, int(steps))


def _plan_dict(plan: Any) -> dict[str, Any]:
    if isinstance(plan, dict):
        return plan
    if hasattr(plan, "to_dict"):
        return plan.to_dict()
    raise invalid("plan", plan, "must be a PlanResult or its dict / JSON form")


def verify_plan(
    plan: Any, scenario: Any = None, *, link_radius_mm: float | None = None
) -> VerifyReport:
    """Replay ``plan`` (a ``PlanResult``, or the dict / JSON of ``sixaxis plan``) in MuJoCo.

    ``scenario`` gives the arm (default: the paper's) and the obstacle boxes of a physical
    world (``obstacle_boxes_mm``); the obstacle cells are always the plan's own
    (``plan.obstacles``, those of the scenario it was made for, not the points added by
    re-planning). Eq. 11 is measured to the cells' centres and to the centres of boxes whose
    distances are taken to the centre (the paper's cubes re-gridded). ``link_radius_mm``
    overrides the capsule radius (default: the scenario's capsules model, else the export's
    default of 30 mm).
    """
    mujoco = require("mujoco", "verify_plan")
    p = _plan_dict(plan)
    poses = np.asarray(p.get("poses_rad") or [], dtype=np.float64).reshape(-1, 6)
    if len(poses) < 1:
        raise invalid("plan", "no poses", "verify_plan needs a plan with poses (a success)")
    s = scenario if isinstance(scenario, _core.Scenario) else _core.Scenario(scenario)
    obstacles = [tuple(int(v) for v in c) for c in p["obstacles"]]
    changes: dict[str, Any] = {"obstacles": obstacles}
    if link_radius_mm is not None:
        changes["planning"] = {
            "clearance_model": {
                "kind": "capsules",
                "link_radius_mm": link_radius_mm,
                "margin_mm": 0,
            }
        }
    s = s.replace(**changes)
    cell_mm = float(p.get("cell_mm", s.cell_mm))
    steps = int(p.get("interpolation_steps", 50))
    model = mujoco.MjModel.from_xml_string(_core.export_scenario(s, "mjcf"))
    data = mujoco.MjData(model)
    geom_names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(model.ngeom)]
    arm = [g for g, n in enumerate(geom_names) if n and n.startswith("seg")]
    obst = [g for g, n in enumerate(geom_names) if n and n.startswith("obstacle")]
    radius_mm = float(model.geom_size[arm[0], 0]) * 1000.0
    path = [tuple(int(v) for v in c) for c in p["path"]]
    fromto = np.zeros(6)
    moves = []
    for k in range(len(poses) - 1):
        best, closest, contact_steps = np.inf, ("", ""), []
        qs = interpolate(poses[k], poses[k + 1], steps)
        for i, q in enumerate(qs):
            data.qpos[:] = q
            mujoco.mj_forward(model, data)
            if data.ncon > 0:
                contact_steps.append(i)
            for a in arm:
                for o in obst:
                    dist = mujoco.mj_geomDistance(model, data, a, o, 10.0, fromto)
                    if dist < best:
                        best, closest = dist, (geom_names[a], geom_names[o])
        # Eq. 11 to the obstacle cells' and the centre boxes' centres, by the core.
        eq11 = float(np.min(_core.centres_clearance_cells(s, qs, cell_mm)))
        moves.append(
            MoveCheck(
                index=k,
                from_cell=path[k],
                to_cell=path[k + 1],
                min_distance_mm=float(best) * 1000.0,
                centre_line_mm=float(best) * 1000.0 + radius_mm,
                eq11_cells=float(eq11),
                contact_steps=contact_steps,
                closest=closest,
            )
        )
    return VerifyReport(link_radius_mm=radius_mm, interpolation_steps=steps, moves=moves)


def _capsules(s: _core.Scenario, radius_mm: float) -> _core.Scenario:
    return s.replace(
        planning={
            "clearance_model": {"kind": "capsules", "link_radius_mm": radius_mm, "margin_mm": 0.0}
        }
    )


def table(seed: int = 0, radius_mm: float = TABLE_LINK_RADIUS_MM) -> list[dict[str, Any]]:
    """Every shipped scenario planned under both clearance models and replayed in MuJoCo
    (capsules of ``radius_mm``): one row per (scenario, model)."""
    rows = []
    for name in _core.Scenario.builtin_names():
        base = _core.Scenario(name)
        for model, s in (("centres (eq. 11)", base), ("capsules", _capsules(base, radius_mm))):
            result = _core.plan(s, seed=seed)
            row: dict[str, Any] = {
                "scenario": name,
                "model": model,
                "success": result.success,
                "replans": result.replans,
                "moves": max(len(result.path) - 1, 0),
                "failure": result.failure,
            }
            if result.success:
                r = verify_plan(result, s, link_radius_mm=radius_mm)
                row.update(
                    eq11_cells=round(r.eq11_cells, 3),
                    centre_line_mm=round(r.centre_line_mm, 2),
                    capsule_mm=round(r.min_distance_mm, 2),
                    contact_steps=r.contacts,
                    moves_in_contact=sum(1 for m in r.moves if m.contact_steps),
                )
            rows.append(row)
    return rows


def markdown(rows: list[dict[str, Any]], radius_mm: float = TABLE_LINK_RADIUS_MM) -> str:
    head = (
        "| scenario | planned with | plan found | moves | eq. 11 min (cells) | "
        f"centre line to a cube (mm) | {radius_mm:g} mm capsule to a cube (mm) | "
        "moves in contact (MuJoCo) |\n|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for r in rows:
        if r["success"]:
            lines.append(
                f"| {r['scenario']} | {r['model']} | yes ({r['replans']} re-plans) | "
                f"{r['moves']} | {r['eq11_cells']:.3f} | {r['centre_line_mm']:.2f} | "
                f"{r['capsule_mm']:.2f} | {r['moves_in_contact']} |"
            )
        else:
            lines.append(f"| {r['scenario']} | {r['model']} | no: {r['failure']} | | | | | |")
    return head + "\n".join(lines) + "\n"


def plan_argument_parser(prog: str, doc: str) -> argparse.ArgumentParser:
    """A parser with the plan options shared by the verify and animate command lines."""
    ap = argparse.ArgumentParser(prog=prog, description=doc.split("\n\n")[0])
    ap.add_argument("--scenario", default=None, help="scenario name or file (default: paper's)")
    ap.add_argument("--plan", default=None, help="a plan JSON (sixaxis plan --out); else plan now")
    ap.add_argument("--seed", type=int, default=0, help="seed of the plan made here")
    return ap


def plan_of_args(args: argparse.Namespace, s: _core.Scenario) -> Any:
    """The plan of ``--plan`` (its JSON), or a new plan of ``s`` with ``--seed``."""
    if args.plan:
        with open(args.plan) as f:
            return json.load(f)
    return _core.plan(s, seed=args.seed)


def main(argv: list[str] | None = None) -> int:
    ap = plan_argument_parser("python -m sixaxis_avoid.verify", __doc__)
    ap.add_argument("--link-radius-mm", type=float, default=None, help="capsule radius, mm")
    ap.add_argument("--table", action="store_true", help="every shipped scenario, both models")
    ap.add_argument("--json", default=None, help="write the report as JSON here")
    args = ap.parse_args(argv)
    if args.table:
        rows = table(args.seed, args.link_radius_mm or TABLE_LINK_RADIUS_MM)
        print(markdown(rows, args.link_radius_mm or TABLE_LINK_RADIUS_MM))
        out: Any = rows
    else:
        s = _core.Scenario(args.scenario)
        plan = plan_of_args(args, s)
        if _plan_dict(plan).get("success") is False:
            print(f"no plan to verify: {_plan_dict(plan).get('failure')}", file=sys.stderr)
            return 1
        report = verify_plan(plan, s, link_radius_mm=args.link_radius_mm)
        print(f"capsule radius {report.link_radius_mm:g} mm, t = {report.interpolation_steps}")
        print("move  from -> to          eq11(cells)  centre line(mm)  capsule(mm)  contacts")
        for m in report.moves:
            print(
                f"{m.index:4d}  {m.from_cell} -> {m.to_cell}  {m.eq11_cells:10.3f}  "
                f"{m.centre_line_mm:15.2f}  {m.min_distance_mm:11.2f}  {len(m.contact_steps)}"
            )
        out = report.to_dict()
    if args.json:
        _core.write_atomic(args.json, json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
