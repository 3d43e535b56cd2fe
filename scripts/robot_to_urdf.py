#!/usr/bin/python3
"""Writes a robot file (TOML, DH rows) as a URDF file and its pumasim side file.

    /usr/bin/python3 scripts/robot_to_urdf.py ROBOT.toml [--out FILE.urdf] [--check]

The URDF (default: ROBOT.urdf beside the robot file) has one link per DH link
and one joint per DH joint, whose frame is the robot's joint frame j (the z
axis on joint j's axis, turned by q_j about it or moved by q_j along it, as
models/dynamics/robot_model.cpp's joint_frames builds it):

  standard DH: joint frame j = DH frame j-1 * Rz(offset_j)            (revolute)
                                           * Rz(theta_j) Tz(offset_j)  (prismatic)
               DH frame j-1  = joint frame j-1 * Tz(d_{j-1}) Tx(a_{j-1}) Rx(alpha_{j-1})
               (d_{j-1} = 0 for a prismatic joint j-1, whose d is its variable)
  modified DH: joint frame j = DH frame j = DH frame j-1
               * Rx(alpha_{j-1}) Tx(a_{j-1}) Rz(offset_j or theta_j) Tz(d_j or offset_j)

so each joint's <origin> is the fixed part of that transform and its axis is
z. Link j's centre of mass and inertia are given in DH frame j, which is the
<inertial> frame (origin: DH frame j in joint frame j). A fixed joint "flange"
places the last DH frame (the robot file's flange) in the last link. The
joint limits are the robot file's (effort and velocity, which URDF requires
and pumasim does not read, are written as 0). A link of no mass and no inertia
has no <inertial>.

What URDF has no place for goes into the side file FILE.urdf.toml (format in
models/robots/README.md): gravity, each joint's rotor inertia, gear ratio and
inconsistent_inertia excuse, and the named poses.

--check writes nothing and exits 1 when the files differ from what it would
write (CTest's GeneratedSources.UrdfIsCurrent runs it on the shipped files).
"""

import argparse
import json
import math
import sys
import tomllib
from pathlib import Path


def cos_sin(a):
    """cos a and sin a, with the rounding of a multiple of pi/2 (cos(pi/2) = 6e-17) removed."""
    c, s = math.cos(a), math.sin(a)
    return (0.0 if abs(c) < 1e-15 else c), (0.0 if abs(s) < 1e-15 else s)


def rot_x(a):
    c, s = cos_sin(a)
    return [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]


def rot_z(a):
    c, s = cos_sin(a)
    return [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]


def matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def apply(A, v):
    return [sum(A[i][k] * v[k] for k in range(3)) for i in range(3)]


def add(u, v):
    return [a + b for a, b in zip(u, v)]


def rpy_of(R):
    """URDF's roll, pitch, yaw of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    pitch = math.atan2(-R[2][0], math.hypot(R[0][0], R[1][0]))
    if math.hypot(R[0][0], R[1][0]) < 1e-12:  # gimbal lock: roll carries the rest
        return [math.atan2(-R[1][2], R[1][1]), pitch, 0.0]
    return [math.atan2(R[2][1], R[2][2]), pitch, math.atan2(R[1][0], R[0][0])]


def num(x):
    """The shortest text that reads back as x (repr), without a negative zero."""
    return repr(float(x) + 0.0)


def nums(v):
    return " ".join(num(x) for x in v)


def distal(J):
    """The part of standard DH row J after the joint: Tz(d) Tx(a) Rx(alpha) as (R, p)."""
    d = 0.0 if J.get("type") == "prismatic" else J["d"]
    return rot_x(J["alpha"]), [J["a"], 0.0, d]


def fixed_part(J, standard):
    """The transform before joint J's variable: (R, p), and its rotation as (alpha, angle) when simple."""
    prismatic = J.get("type") == "prismatic"
    angle = J.get("theta", 0.0) if prismatic else J.get("offset", 0.0)
    slide = J.get("offset", 0.0) if prismatic else (0.0 if standard else J["d"])
    R = rot_z(angle)
    return R, apply(R, [0.0, 0.0, slide])


def joint_origin(joints, j, standard):
    """Joint frame j in joint frame j-1 (the base frame for j = 0) as (R, p)."""
    R, p = [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], [0.0, 0.0, 0.0]
    if standard and j > 0:
        R, p = distal(joints[j - 1])
    elif not standard:
        R, p = rot_x(joints[j]["alpha"]), [joints[j]["a"], 0.0, 0.0]
    Rf, pf = fixed_part(joints[j], standard)
    return matmul(R, Rf), add(p, apply(R, pf))


def origin_xml(R, p, alpha=None):
    """An <origin>: rpy from R, or (alpha, 0, 0) exactly when R is Rx(alpha)."""
    rpy = [alpha, 0.0, 0.0] if alpha is not None else rpy_of(R)
    return f'<origin xyz="{nums(p)}" rpy="{nums(rpy)}"/>'


def is_rot_x(J, standard, j):
    """Joint j's origin rotation is Rx(alpha) of the row before (no fixed angle about z)."""
    prismatic = J[j].get("type") == "prismatic"
    angle = J[j].get("theta", 0.0) if prismatic else J[j].get("offset", 0.0)
    if angle != 0.0:
        return None
    if standard:
        return J[j - 1]["alpha"] if j > 0 else 0.0
    return J[j]["alpha"]


def limit_xml(J, j):
    """The joint's <limit>: the robot file's limits; a revolute joint's default is +-pi there."""
    prismatic = J.get("type") == "prismatic"
    if "limits" not in J and prismatic:
        raise SystemExit(f"joint {j + 1}: a prismatic joint without limits has no URDF form (URDF requires them)")
    lo, hi = J.get("limits", [-math.pi, math.pi])
    return f'    <limit lower="{num(lo)}" upper="{num(hi)}" effort="0" velocity="0"/>\n'


def joint_xml(joints, j, standard):
    J = joints[j]
    R, p = joint_origin(joints, j, standard)
    kind = "prismatic" if J.get("type") == "prismatic" else "revolute"
    limit = limit_xml(J, j)
    parent = "base" if j == 0 else f"link{j}"
    return (f'  <joint name="joint{j + 1}" type="{kind}">\n'
            f'    <parent link="{parent}"/>\n    <child link="link{j + 1}"/>\n'
            f'    {origin_xml(R, p, is_rot_x(joints, standard, j))}\n'
            f'    <axis xyz="0 0 1"/>\n{limit}  </joint>\n')


def link_xml(J, j, standard):
    m, c, I = J["mass"], J["com"], J["inertia"]
    if m == 0 and all(x == 0 for x in I):
        return f'  <link name="link{j + 1}"/>\n'
    R, p = distal(J) if standard else ([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], [0.0, 0.0, 0.0])
    com = add(p, apply(R, c))
    alpha = J["alpha"] if standard else 0.0
    ixx, iyy, izz, ixy, iyz, ixz = I
    return (f'  <link name="link{j + 1}">\n    <inertial>\n'
            f'      <origin xyz="{nums(com)}" rpy="{nums([alpha, 0.0, 0.0])}"/>\n'
            f'      <mass value="{num(m)}"/>\n'
            f'      <inertia ixx="{num(ixx)}" ixy="{num(ixy)}" ixz="{num(ixz)}" '
            f'iyy="{num(iyy)}" iyz="{num(iyz)}" izz="{num(izz)}"/>\n'
            f'    </inertial>\n  </link>\n')


def urdf_text(doc, source, out):
    robot, joints = doc["robot"], doc["joint"]
    standard = robot["convention"] == "standard"
    n = len(joints)
    R, p = distal(joints[-1]) if standard else ([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]], [0.0, 0.0, 0.0])
    flange_alpha = joints[-1]["alpha"] if standard else 0.0
    body = '  <link name="base"/>\n'
    for j in range(n):
        body += joint_xml(joints, j, standard) + link_xml(joints[j], j, standard)
    body += (f'  <joint name="flange" type="fixed">\n    <parent link="link{n}"/>\n    <child link="flange"/>\n'
             f'    {origin_xml(R, p, flange_alpha)}\n  </joint>\n  <link name="flange"/>\n')
    default_out = str(Path(source).with_suffix(".urdf"))
    regenerate = f"/usr/bin/python3 scripts/robot_to_urdf.py {source}" + (
        "" if str(out) == default_out else f" with the out option {out}")
    head = ('<?xml version="1.0"?>\n<!-- ' + xml_comment_text(
        f'Generated by scripts/robot_to_urdf.py from {source}; do not edit.\n'
        f'     Regenerate: {regenerate}\n'
        f'     The values and their sources are those of {source}; what URDF has no place\n'
        f'     for (gravity, rotor inertias, gear ratios, poses) is in {Path(out).name}.toml.\n'
        f'     Limits are the robot file\'s; effort and velocity (required by URDF, not read\n'
        f'     by pumasim) are 0.') + ' -->\n')
    return head + f'<robot name="{robot["name"]}">\n' + body + "</robot>\n"


def xml_comment_text(text):
    """text made legal inside an XML comment: no "--" (XML 1.0, sec. 2.5: a comment may not
    contain it; urdfdom tolerates it, strict parsers such as ElementTree and xmllint do not)
    and no "-" at its end."""
    while "--" in text:
        text = text.replace("--", "- -")
    return text + " " if text.endswith("-") else text


def side_text(doc, source, out):
    robot, joints = doc["robot"], doc["joint"]
    lines = [f"# Generated by scripts/robot_to_urdf.py from {source}; do not edit.",
             f"# pumasim's side file of {Path(out).name}: what URDF has no place for (format in",
             "# models/robots/README.md). Values and sources: " + source + ".",
             "", "[robot]", f"gravity = [{', '.join(num(g) for g in robot['gravity'])}]   # m/s^2, base frame", ""]
    for j, J in enumerate(joints):
        lines += [f"[joint.joint{j + 1}]", f"rotor_inertia = {num(J['rotor_inertia'])}   # kg m^2, motor side",
                  f"gear_ratio = {num(J['gear_ratio'])}"]
        if "inconsistent_inertia" in J:
            lines.append(f"inconsistent_inertia = {json.dumps(J['inconsistent_inertia'], ensure_ascii=False)}")
        lines.append("")
    if doc.get("poses"):
        lines.append("[poses]")
        for name, q in doc["poses"].items():
            lines.append(f"{name} = [{', '.join(num(x) for x in q)}]")
        lines.append("")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("robot", help="a robot file (TOML)")
    ap.add_argument("--out", help="the URDF file to write (default: the robot file with .urdf)")
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 when the files are not current")
    a = ap.parse_args()
    out = a.out or str(Path(a.robot).with_suffix(".urdf"))
    with open(a.robot, "rb") as f:
        doc = tomllib.load(f)
    files = {out: urdf_text(doc, a.robot, out), out + ".toml": side_text(doc, a.robot, out)}
    stale = [p for p, text in files.items() if not Path(p).is_file() or Path(p).read_text() != text]
    if a.check:
        for p in stale:
            print(f"robot_to_urdf: {p} is not what scripts/robot_to_urdf.py {a.robot} --out {out} writes;"
                  " regenerate it and commit", file=sys.stderr)
        return 1 if stale else 0
    for p, text in files.items():
        Path(p).write_text(text)
        print(f"robot_to_urdf: wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
