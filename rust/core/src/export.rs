//! Export of a scenario to robotics formats: the arm as URDF, the arm and its world as a
//! MuJoCo MJCF scene.
//!
//! Entry points:
//! - [`urdf`] — the arm of a scenario as a URDF robot: links `base_link`, `link1`..`link6`,
//!   revolute joints `joint1`..`joint6` from the modified D-H table, the auxiliary point as a
//!   fixed frame `aux` and the terminal frame `terminal`.
//! - [`mjcf`] — the whole scene as MJCF: the same kinematic tree with capsule links, the
//!   obstacles as boxes, the target (and start) as sites.
//! - [`export`] / [`ExportFormat`] — either, by name (`sixaxis export --format urdf|mjcf`).
//! - [`link_radius_mm`] — the capsule radius used: the scenario's capsules model, or
//!   [`DEFAULT_LINK_RADIUS_MM`].
//!
//! Conventions, shared by both formats:
//! - Lengths in metres (the core's mm / 1000), angles in radians, as URDF and MuJoCo expect.
//! - Modified D-H row i, `RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i + offset_i) TransZ(d_i)`,
//!   is rewritten as the fixed transform `RotX(alpha_{i-1}) TransX(a_{i-1}) TransZ(d_i)
//!   RotZ(offset_i)` (RotZ and TransZ commute) followed by a rotation by `theta_i` about the
//!   joint's z axis: the fixed part is joint i's origin (URDF) or body i's `pos`/`quat` (MJCF),
//!   the axis is `0 0 1`. Joint value 0 is the D-H `theta_i = 0`, so joint values are the
//!   core's joint angles as they are.
//! - Frame i of the export is frame i of [`Arm`]; the polyline points of
//!   [`Arm::points_mm`] (O1..O6, Aux) are the origins of `link1`..`link6` and of `aux`
//!   (URDF) or sites `O1`..`O6`, `aux` (MJCF), and the terminal frame (`terminal`) is frame 6
//!   (no tool offset).
//! - Each of the polyline's 7 segments is rigid in one link (base→O1 in the base, O1→O2 in
//!   link 1, ..., O3→Aux and Aux→O4 in link 3, O5→O6 in link 5): a capsule of the link
//!   radius (a sphere for a zero-length segment), which is the capsules clearance model's body.
//! - Joint ranges: the scenario's `joint_limits_deg` if set, else (-pi, pi], the range of
//!   every angle the core produces.
//!
//! ```
//! use sixaxis_core::export::{export, ExportFormat};
//! use sixaxis_core::Scenario;
//! let s = Scenario::builtin("paper_simple").unwrap();
//! let urdf = export(&s, ExportFormat::Urdf);
//! assert!(urdf.contains(r#"<joint name="joint1" type="revolute">"#));
//! let mjcf = export(&s, ExportFormat::Mjcf);
//! assert_eq!(mjcf.matches(r#"class="obstacle" pos="#).count(), s.obstacles.len());
//! ```

use std::f64::consts::PI;
use std::fmt::Write;

use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::error::{Error, Result};
use crate::kinematics::Arm;
use crate::scenario::{ClearanceModel, Scenario};

/// Capsule radius of the links when the scenario's clearance model is not `capsules`, mm.
pub const DEFAULT_LINK_RADIUS_MM: f64 = 30.0;

/// An export format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// URDF: the arm alone (kinematic tree with capsule visuals and collisions).
    Urdf,
    /// MuJoCo MJCF: the arm, the obstacles, the target and the start.
    Mjcf,
}

impl std::str::FromStr for ExportFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "urdf" => Ok(ExportFormat::Urdf),
            "mjcf" => Ok(ExportFormat::Mjcf),
            _ => Err(Error::argument("format", s, "must be one of: urdf, mjcf")),
        }
    }
}

/// The scenario exported in `format`.
pub fn export(s: &Scenario, format: ExportFormat) -> String {
    match format {
        ExportFormat::Urdf => urdf(s),
        ExportFormat::Mjcf => mjcf(s),
    }
}

/// Radius of every link capsule, mm: the scenario's capsules model if it has one, else
/// [`DEFAULT_LINK_RADIUS_MM`].
pub fn link_radius_mm(s: &Scenario) -> f64 {
    match s.planning.clearance_model {
        ClearanceModel::Capsules { link_radius_mm, .. } => link_radius_mm,
        ClearanceModel::Centres => DEFAULT_LINK_RADIUS_MM,
    }
}

/// A number for XML: shortest round-trip decimal, with values below 1e-15 in magnitude
/// written as 0 (they are rounding noise of exact right angles).
fn num(v: f64) -> String {
    let v = if v.abs() < 1e-15 { 0.0 } else { v };
    format!("{v}")
}

/// A cosmetic number (sizes of the floor, sites, light): 9 decimals at most.
fn short(v: f64) -> String {
    let t = format!("{v:.9}");
    let t = t.trim_end_matches('0').trim_end_matches('.');
    if t == "-0" {
        "0".into()
    } else {
        t.into()
    }
}

fn short3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", short(v.x), short(v.y), short(v.z))
}

fn vec3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace("--", "- -")
}

/// The fixed part of D-H row `i` (0-based): rotation and translation (mm) of frame i+1 at
/// `theta = 0` in frame i.
fn joint_origin(arm: &Arm, i: usize) -> (Rotation3<f64>, Vector3<f64>) {
    let l = &arm.links[i];
    let p = Vector3::new(l.a, -l.d * l.sa, l.d * l.ca);
    let rx = Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        1.0, 0.0, 0.0, 0.0, l.ca, -l.sa, 0.0, l.sa, l.ca,
    ));
    let r = rx * Rotation3::from_axis_angle(&Vector3::z_axis(), l.offset);
    (r, p)
}

/// The 7 polyline segments, each as (link index 0..=6 that carries it, from, to) in that
/// link's frame, mm. Link 0 is the base.
fn segments(arm: &Arm) -> Vec<(usize, Vector3<f64>, Vector3<f64>)> {
    let o = Vector3::zeros();
    let next = |i: usize| joint_origin(arm, i).1;
    let aux = Vector3::new(arm.links[3].a, 0.0, 0.0);
    vec![
        (0, o, next(0)),
        (1, o, next(1)),
        (2, o, next(2)),
        (3, o, aux),
        (3, aux, next(3)),
        (4, o, next(4)),
        (5, o, next(5)),
    ]
}

/// Joint range, radians.
fn joint_range(s: &Scenario, i: usize) -> (f64, f64) {
    match &s.arm.joint_limits_deg {
        Some(l) => (l[i][0].to_radians(), l[i][1].to_radians()),
        None => (-PI, PI),
    }
}

fn rpy(r: &Rotation3<f64>) -> Vector3<f64> {
    let (roll, pitch, yaw) = r.euler_angles();
    Vector3::new(roll, pitch, yaw)
}

fn header_comment(s: &Scenario, what: &str) -> String {
    format!(
        "<!-- {what} of scenario \"{}\", exported by sixaxis {} (sixaxis export). Lengths in \
         metres (mm / 1000), angles in radians; joint values are the core's joint angles \
         (modified D-H). -->\n",
        xml_escape(&s.name),
        env!("CARGO_PKG_VERSION")
    )
}

/// A URDF `<geometry>` of a capsule segment, with its `<origin>` (metres): a cylinder of the
/// segment's length with spheres at both ends would be three elements, so URDF gets the
/// capsule's core cylinder plus end spheres as separate visuals/collisions.
fn urdf_segment(out: &mut String, a: &Vector3<f64>, b: &Vector3<f64>, r_m: f64, rgba: &str) {
    let (a, b) = (a / 1000.0, b / 1000.0);
    let d = b - a;
    let len = d.norm();
    let mut shapes: Vec<(Vector3<f64>, Vector3<f64>, String)> = Vec::new();
    if len > 1e-12 {
        let rot = Rotation3::rotation_between(&Vector3::z(), &d).unwrap_or_else(|| {
            // d points along -z.
            Rotation3::from_axis_angle(&Vector3::x_axis(), PI)
        });
        shapes.push((
            (a + b) / 2.0,
            rpy(&rot),
            format!(
                "<cylinder radius=\"{}\" length=\"{}\"/>",
                num(r_m),
                num(len)
            ),
        ));
    }
    for p in [a, b] {
        shapes.push((
            p,
            Vector3::zeros(),
            format!("<sphere radius=\"{}\"/>", num(r_m)),
        ));
    }
    for (xyz, rpy, geometry) in shapes {
        for kind in ["visual", "collision"] {
            let _ = write!(
                out,
                "    <{kind}>\n      <origin xyz=\"{}\" rpy=\"{}\"/>\n      <geometry>{geometry}</geometry>\n",
                vec3(&xyz),
                vec3(&rpy)
            );
            if kind == "visual" {
                let _ = writeln!(
                    out,
                    "      <material name=\"arm\"><color rgba=\"{rgba}\"/></material>"
                );
            }
            let _ = writeln!(out, "    </{kind}>");
        }
    }
}

/// The arm of `s` as a URDF robot named `sixaxis_<scenario name>`.
///
/// Links `base_link`, `link1`..`link6` (frame i of the D-H table), `aux` (the auxiliary
/// point "joint 3.5", fixed to `link3`) and `terminal` (frame 6, fixed to `link6`); joints
/// `joint1`..`joint6` revolute about z. Every link carries its polyline segments as capsules
/// (cylinder + end spheres) of [`link_radius_mm`], in `<visual>` and `<collision>`. No
/// inertias: the model is kinematic.
pub fn urdf(s: &Scenario) -> String {
    let arm = s.arm();
    let r_m = link_radius_mm(s) / 1000.0;
    let segs = segments(&arm);
    let rgba = "0.25 0.45 0.8 1";
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    out += &header_comment(s, "The arm");
    let _ = writeln!(out, "<robot name=\"sixaxis_{}\">", xml_escape(&s.name));
    let link_names = [
        "base_link",
        "link1",
        "link2",
        "link3",
        "link4",
        "link5",
        "link6",
    ];
    for (k, name) in link_names.iter().enumerate() {
        let _ = writeln!(out, "  <link name=\"{name}\">");
        for (_, a, b) in segs.iter().filter(|(l, _, _)| *l == k) {
            urdf_segment(&mut out, a, b, r_m, rgba);
        }
        let _ = writeln!(out, "  </link>");
    }
    out += "  <link name=\"aux\"/>\n  <link name=\"terminal\"/>\n";
    for i in 0..6 {
        let (r, p) = joint_origin(&arm, i);
        let (lo, hi) = joint_range(s, i);
        let _ = write!(
            out,
            "  <joint name=\"joint{}\" type=\"revolute\">\n    <parent link=\"{}\"/>\n    \
             <child link=\"{}\"/>\n    <origin xyz=\"{}\" rpy=\"{}\"/>\n    <axis xyz=\"0 0 1\"/>\n    \
             <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>\n  </joint>\n",
            i + 1,
            link_names[i],
            link_names[i + 1],
            vec3(&(p / 1000.0)),
            vec3(&rpy(&r)),
            num(lo),
            num(hi)
        );
    }
    let aux = Vector3::new(arm.links[3].a, 0.0, 0.0) / 1000.0;
    let _ = write!(
        out,
        "  <joint name=\"aux_joint\" type=\"fixed\">\n    <parent link=\"link3\"/>\n    \
         <child link=\"aux\"/>\n    <origin xyz=\"{}\" rpy=\"0 0 0\"/>\n  </joint>\n  \
         <joint name=\"terminal_joint\" type=\"fixed\">\n    <parent link=\"link6\"/>\n    \
         <child link=\"terminal\"/>\n    <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n  </joint>\n",
        vec3(&aux)
    );
    out += "</robot>\n";
    out
}

fn mjcf_quat(r: &Rotation3<f64>) -> String {
    let q = UnitQuaternion::from_rotation_matrix(r);
    format!("{} {} {} {}", num(q.w), num(q.i), num(q.j), num(q.k))
}

fn mjcf_segment(out: &mut String, indent: &str, name: &str, a: &Vector3<f64>, b: &Vector3<f64>) {
    let (a, b) = (a / 1000.0, b / 1000.0);
    if (b - a).norm() > 1e-12 {
        let _ = writeln!(
            out,
            "{indent}<geom name=\"{name}\" class=\"arm\" type=\"capsule\" fromto=\"{} {}\"/>",
            vec3(&a),
            vec3(&b)
        );
    } else {
        let _ = writeln!(
            out,
            "{indent}<geom name=\"{name}\" class=\"arm\" type=\"sphere\" pos=\"{}\"/>",
            vec3(&a)
        );
    }
}

/// The scene of `s` as a MuJoCo MJCF model named `sixaxis_<scenario name>`.
///
/// Bodies `link1`..`link6` nest as the D-H chain with hinge joints `joint1`..`joint6`
/// (`qpos` = the core's joint angles); geoms `seg0`..`seg6` are the polyline's segments as
/// capsules of [`link_radius_mm`] (spheres when a segment has zero length; class `arm`);
/// sites `O1`..`O6`, `aux` and `terminal` mark the polyline's points. Obstacles are box geoms
/// `obstacle<k>` (class `obstacle`, the cube of one cell around each obstacle cell, in the
/// order of the scenario); sites `target` and `start` mark those cells' centres; a
/// transparent site `bounds` shows the scenario's box of cells. Arm geoms only collide with
/// obstacle geoms (contype/conaffinity), so every contact MuJoCo reports is arm–obstacle. No
/// gravity: the model is for kinematic replay (`qpos` → `mj_forward`).
pub fn mjcf(s: &Scenario) -> String {
    let arm = s.arm();
    let r_m = link_radius_mm(s) / 1000.0;
    let cell_m = s.cell_mm / 1000.0;
    let segs = segments(&arm);
    let mut out = String::new();
    out += &header_comment(s, "The scene");
    let _ = write!(
        out,
        "<mujoco model=\"sixaxis_{}\">\n  <compiler angle=\"radian\" autolimits=\"true\" boundmass=\"1e-6\" boundinertia=\"1e-9\"/>\n  \
         <option gravity=\"0 0 0\"/>\n  <visual>\n    <global offwidth=\"1280\" offheight=\"960\"/>\n  </visual>\n  \
         <default>\n    <default class=\"arm\">\n      <geom size=\"{}\" contype=\"1\" conaffinity=\"2\" \
         rgba=\"0.25 0.45 0.8 1\"/>\n    </default>\n    <default class=\"obstacle\">\n      \
         <geom type=\"box\" contype=\"2\" conaffinity=\"1\" rgba=\"0.55 0.57 0.62 1\"/>\n    </default>\n  \
         </default>\n  <worldbody>\n",
        xml_escape(&s.name),
        num(r_m)
    );
    // Cell coordinates to metres, through mm (0.3, not 0.30000000000000004).
    let to_m = |c: [i32; 3], shift_cells: f64| {
        Vector3::from(c.map(|v| (f64::from(v) + shift_cells) * s.cell_mm)) / 1000.0
    };
    let lo = to_m(s.bounds.min, -0.5);
    let hi = to_m(s.bounds.max, 0.5);
    let _ = write!(
        out,
        "    <light pos=\"{}\" dir=\"0 0 -1\" directional=\"true\"/>\n    \
         <geom name=\"floor\" type=\"plane\" pos=\"{}\" size=\"{}\" contype=\"0\" conaffinity=\"0\" \
         rgba=\"0.9 0.9 0.92 1\"/>\n    \
         <site name=\"bounds\" type=\"box\" pos=\"{}\" size=\"{}\" rgba=\"0.5 0.5 0.6 0.06\"/>\n",
        short3(&Vector3::new(0.0, 0.0, hi.z + 2.0)),
        short3(&Vector3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z)),
        short3(&Vector3::new((hi.x - lo.x) / 2.0 + cell_m, (hi.y - lo.y) / 2.0 + cell_m, 0.01)),
        short3(&((lo + hi) / 2.0)),
        short3(&((hi - lo) / 2.0)),
    );
    let site = |out: &mut String, indent: &str, name: &str, p: &Vector3<f64>, rgba: &str| {
        let _ = writeln!(
            out,
            "{indent}<site name=\"{name}\" pos=\"{}\" size=\"{}\" rgba=\"{rgba}\"/>",
            short3(p),
            short(r_m * 0.6)
        );
    };
    let mut seg_index = 0;
    for (_, a, b) in segs.iter().filter(|(l, _, _)| *l == 0) {
        mjcf_segment(&mut out, "    ", &format!("seg{seg_index}"), a, b);
        seg_index += 1;
    }
    let mut indent = String::from("    ");
    for i in 0..6 {
        let (r, p) = joint_origin(&arm, i);
        let (lo_q, hi_q) = joint_range(s, i);
        let _ = writeln!(
            out,
            "{indent}<body name=\"link{}\" pos=\"{}\" quat=\"{}\">",
            i + 1,
            vec3(&(p / 1000.0)),
            mjcf_quat(&r)
        );
        indent += "  ";
        let _ = writeln!(
            out,
            "{indent}<joint name=\"joint{}\" type=\"hinge\" axis=\"0 0 1\" range=\"{} {}\"/>",
            i + 1,
            num(lo_q),
            num(hi_q)
        );
        site(
            &mut out,
            &indent,
            &format!("O{}", i + 1),
            &Vector3::zeros(),
            "0.1 0.2 0.4 1",
        );
        for (_, a, b) in segs.iter().filter(|(l, _, _)| *l == i + 1) {
            mjcf_segment(&mut out, &indent, &format!("seg{seg_index}"), a, b);
            seg_index += 1;
        }
        if i == 2 {
            let aux = Vector3::new(arm.links[3].a, 0.0, 0.0) / 1000.0;
            site(&mut out, &indent, "aux", &aux, "0.1 0.2 0.4 1");
        }
        if i == 5 {
            site(
                &mut out,
                &indent,
                "terminal",
                &Vector3::zeros(),
                "0.85 0.2 0.2 1",
            );
        }
    }
    for _ in 0..6 {
        indent.truncate(indent.len() - 2);
        let _ = writeln!(out, "{indent}</body>");
    }
    let h = cell_m / 2.0;
    for (k, c) in s.obstacles.iter().enumerate() {
        let centre = to_m(*c, 0.0);
        let _ = writeln!(
            out,
            "    <geom name=\"obstacle{k}\" class=\"obstacle\" pos=\"{}\" size=\"{} {} {}\"/>",
            vec3(&centre),
            num(h),
            num(h),
            num(h)
        );
    }
    // Obstacle boxes of a physical world (`obstacle_boxes_mm`), after the unit cubes.
    let first_box = s.obstacles.len();
    for (k, b) in s.obstacle_boxes_mm.iter().enumerate() {
        let centre: Vector3<f64> = (Vector3::from(b.min_mm) + Vector3::from(b.max_mm)) / 2000.0;
        let half: Vector3<f64> = (Vector3::from(b.max_mm) - Vector3::from(b.min_mm)) / 2000.0;
        let _ = writeln!(
            out,
            "    <geom name=\"obstacle{}\" class=\"obstacle\" pos=\"{}\" size=\"{} {} {}\"/>",
            first_box + k,
            vec3(&centre),
            num(half.x),
            num(half.y),
            num(half.z)
        );
    }
    for (name, c, rgba) in [
        ("target", s.target, "0.18 0.67 0.35 0.8"),
        ("start", s.start, "0.85 0.55 0.1 0.8"),
    ] {
        let _ = writeln!(
            out,
            "    <site name=\"{name}\" type=\"sphere\" pos=\"{}\" size=\"{}\" rgba=\"{rgba}\"/>",
            vec3(&to_m(c, 0.0)),
            short(cell_m * 0.2)
        );
    }
    out += "  </worldbody>\n</mujoco>\n";
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::PAPER_BETA0_DEG;

    /// A physical world's boxes (mm) become MJCF boxes (m) after the unit cubes.
    #[test]
    fn obstacle_boxes_are_exported() {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        s.obstacle_boxes_mm.push(crate::scenario::ObstacleBox {
            min_mm: [-500.0, 400.0, 100.0],
            max_mm: [-300.0, 500.0, 400.0],
            distance_to: Default::default(),
        });
        let mjcf = export(&s, ExportFormat::Mjcf);
        let n = s.obstacles.len();
        assert_eq!(mjcf.matches(r#"class="obstacle" pos="#).count(), n + 1);
        let line = mjcf
            .lines()
            .find(|l| l.contains(&format!("name=\"obstacle{n}\"")))
            .unwrap();
        assert!(line.contains(r#"pos="-0.4 0.45 0.25""#), "{line}");
        assert!(line.contains(r#"size="0.1 0.05 0.15""#), "{line}");
    }

    /// Frame i+1 from frame i through the export's fixed transform and a rotation about z
    /// equals the core's D-H step.
    #[test]
    fn joint_origins_chain_to_the_core_fk() {
        let arm = Arm::paper();
        let q = PAPER_BETA0_DEG.map(f64::to_radians);
        let mut r = Rotation3::identity();
        let mut p = Vector3::zeros();
        let pts = arm.points_mm(&q);
        let mut origins = Vec::new();
        for (i, qi) in q.iter().enumerate() {
            let (ri, pi) = joint_origin(&arm, i);
            p += r * pi;
            r = r * ri * Rotation3::from_axis_angle(&Vector3::z_axis(), *qi);
            origins.push(p);
        }
        let fk = arm.fk(&q);
        assert!((p - fk.position_mm).norm() < 1e-9);
        assert!((r.matrix() - fk.rotation).amax() < 1e-12);
        for (k, o) in [1, 2, 3, 5, 6, 7].iter().zip(&origins) {
            assert!((pts[*k] - o).norm() < 1e-9, "O{k}");
        }
    }

    #[test]
    fn formats_parse_and_name_the_bad_value() {
        assert_eq!("urdf".parse::<ExportFormat>().unwrap(), ExportFormat::Urdf);
        assert_eq!("mjcf".parse::<ExportFormat>().unwrap(), ExportFormat::Mjcf);
        let e = "sdf".parse::<ExportFormat>().unwrap_err().to_string();
        assert!(e.contains("format") && e.contains("sdf"), "{e}");
    }

    #[test]
    fn urdf_has_the_links_joints_and_frames() {
        let s = Scenario::builtin("paper_simple").unwrap();
        let u = urdf(&s);
        for name in ["base_link", "link1", "link6", "aux", "terminal"] {
            assert!(u.contains(&format!("<link name=\"{name}\"")), "{name}");
        }
        assert_eq!(u.matches("type=\"revolute\"").count(), 6);
        assert_eq!(u.matches("type=\"fixed\"").count(), 2);
        // Row 4: a_3 = -300 mm, d_4 = 106 mm, alpha_3 = 0.
        assert!(
            u.contains("<origin xyz=\"-0.3 0 0.106\" rpy=\"0 0 0\"/>"),
            "{u}"
        );
    }

    #[test]
    fn mjcf_capsule_radius_follows_the_clearance_model() {
        let mut s = Scenario::builtin("paper_simple").unwrap();
        assert_eq!(link_radius_mm(&s), DEFAULT_LINK_RADIUS_MM);
        assert!(mjcf(&s).contains("<geom size=\"0.03\""));
        s.planning.clearance_model = ClearanceModel::Capsules {
            link_radius_mm: 45.0,
            margin_mm: 0.0,
        };
        let m = mjcf(&s);
        assert!(m.contains("<geom size=\"0.045\""));
        assert_eq!(m.matches("class=\"arm\" type=").count(), 7);
        assert_eq!(m.matches("<body ").count(), 6);
        assert!(m.contains("<site name=\"target\" type=\"sphere\" pos=\"0 0.3 0\""));
    }
}
