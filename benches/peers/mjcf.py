"""MJCF (MuJoCo) from a satsim scene: the scene's model file, hinge springs, reaction wheels
and initial state, for the peer comparison of benches/peers/peers.py.

Conventions (satsim's, cli-contract.md section 1): body frames as in the model file; a hinge
joins `parent` and `child` at `at` (parent frame) = `child_at` (child frame), turns about
`axis` (parent frame, unit), with the fixed child-to-parent rotation `rotation`
([w, x, y, z], Hamilton) at zero angle. In MJCF each satsim body is a <body> whose frame is
the satsim body frame at zero angles: pos = at - R0 child_at, quat = rotation; the hinge is a
<joint> with pos = child_at and axis = R0^T axis (child frame).

A chain of massless zero-length links (mass 0, inertia 0, one child, the next hinge at the
link origin, no fixed rotation) becomes several joints in one MuJoCo body, in chain order:
MuJoCo applies a body's joints in order, each about its axis rotated by the ones before,
which is the chain's kinematics. Reaction wheels are child bodies of the root on hinges
through their centres (mass, axial and transverse inertia as in the scene). Hinge springs
and dampers are joint stiffness / damping (springref = reference). Gravity, contacts and
every other effect are off; the scene must have no other effects (checked).

    python3 mjcf.py SCENE.toml > scene.xml
"""

import math
import sys
import tomllib
from pathlib import Path


def quat_to_mat(q):
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def mat_vec(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def mat_t_vec(m, v):
    return [sum(m[k][i] * v[k] for k in range(3)) for i in range(3)]


def fmt(v):
    return " ".join(repr(float(x)) for x in v)


class SceneError(Exception):
    pass


def load(scene_path):
    """The scene (dict), the model (dict) and the scene's directory."""
    scene_path = Path(scene_path)
    scene = tomllib.loads(scene_path.read_text())
    model_path = (scene_path.parent / scene["model"]).resolve()
    model = tomllib.loads(model_path.read_text())
    return scene, model


def write(scene_path, timestep=None, integrator="RK4"):
    """MJCF text, and the layout needed to compare states: (hinge names in model order,
    the MuJoCo joint name of each, wheel names)."""
    scene, model = load(scene_path)
    effects = scene.get("effects", {})
    unknown = set(effects) - {"hinge_springs", "reaction_wheels"}
    if unknown or "orbit" in scene:
        raise SceneError(f"{scene_path}: only hinge springs and wheels are written; got {sorted(unknown)}")
    if model.get("base", {}).get("kind", "free") != "free":
        raise SceneError("only a free base is written")
    bodies = {b["name"]: b for b in model["body"]}
    root = model["body"][0]["name"]
    hinges = model.get("hinge", [])
    names = [h["name"] for h in hinges]
    springs = effects.get("hinge_springs", {})
    k = springs.get("stiffness", [0.0] * len(hinges))
    c = springs.get("damping", [0.0] * len(hinges))
    ref = springs.get("reference", [0.0] * len(hinges))
    children = {}
    for i, h in enumerate(hinges):
        children.setdefault(h["parent"], []).append(i)

    def massless(name):
        b = bodies[name]
        return b.get("mass", 0.0) == 0.0 and all(x == 0.0 for row in b.get("inertia", [[0] * 3] * 3) for x in row)

    def joint_xml(i, child_at, rot, indent):
        h = hinges[i]
        axis = mat_t_vec(rot, h["axis"])  # child frame
        return (
            f'{indent}<joint name="{h["name"]}" type="hinge" pos="{fmt(child_at)}" axis="{fmt(axis)}" '
            f'stiffness="{k[i]!r}" damping="{c[i]!r}" springref="{ref[i]!r}" armature="{h.get("armature", 0.0)!r}"/>\n'
        )

    out = []

    def body_xml(i, indent):
        """Body for hinge i, merging massless zero-length links below it."""
        chain = [i]
        while massless(hinges[chain[-1]]["child"]):
            link = hinges[chain[-1]]["child"]
            kids = children.get(link, [])
            h = hinges[chain[-1]]
            nxt = hinges[kids[0]] if len(kids) == 1 else None
            if (
                nxt is None
                or any(x != 0.0 for x in h.get("child_at", [0, 0, 0]))
                or any(x != 0.0 for x in nxt.get("at", [0, 0, 0]))
                or nxt.get("rotation", [1, 0, 0, 0]) != [1, 0, 0, 0]
                or h.get("rotation", [1, 0, 0, 0]) != [1, 0, 0, 0]
            ):
                raise SceneError(f"massless body `{link}` is not a zero-length link of a chain")
            chain.append(kids[0])
        first, last = hinges[chain[0]], hinges[chain[-1]]
        name = last["child"]
        b = bodies[name]
        rot = quat_to_mat(first.get("rotation", [1.0, 0.0, 0.0, 0.0]))
        child_at = last.get("child_at", [0.0, 0.0, 0.0])
        at = first.get("at", [0.0, 0.0, 0.0])
        pos = [a - r for a, r in zip(at, mat_vec(rot, child_at))]
        out.append(f'{indent}<body name="{name}" pos="{fmt(pos)}" quat="{fmt(first.get("rotation", [1, 0, 0, 0]))}">\n')
        for j in chain:
            out.append(joint_xml(j, child_at, rot, indent + "  "))
        inertial(b, indent + "  ")
        for j in children.get(name, []):
            body_xml(j, indent + "  ")
        out.append(f"{indent}</body>\n")

    def inertial(b, indent):
        ii = b["inertia"]
        full = [ii[0][0], ii[1][1], ii[2][2], ii[0][1], ii[0][2], ii[1][2]]
        out.append(
            f'{indent}<inertial pos="{fmt(b.get("com", [0, 0, 0]))}" mass="{b["mass"]!r}" fullinertia="{fmt(full)}"/>\n'
        )

    ts = timestep if timestep is not None else scene["integrator"]["step"]
    out.append('<mujoco model="satsim-peer">\n')
    out.append('  <compiler angle="radian" autolimits="true"/>\n')
    out.append(f'  <option timestep="{ts!r}" integrator="{integrator}" gravity="0 0 0">\n')
    out.append('    <flag contact="disable" constraint="disable" gravity="disable"/>\n')
    out.append("  </option>\n  <worldbody>\n")
    out.append(f'    <body name="{root}">\n      <freejoint name="base"/>\n')
    inertial(bodies[root], "      ")
    wheels = []
    for w in effects.get("reaction_wheels", {}).get("wheel", []):
        for key in w:
            if key not in ("name", "axis", "inertia", "transverse", "mass", "at", "speed"):
                raise SceneError(f"wheel `{w['name']}`: `{key}` is not written")
        a = w["axis"]
        n = math.sqrt(sum(x * x for x in a))
        a = [x / n for x in a]
        ja, jt = w["inertia"], w.get("transverse", 0.5 * w["inertia"])
        i3 = [[ja * a[r] * a[s] + jt * ((r == s) - a[r] * a[s]) for s in range(3)] for r in range(3)]
        wname = f"wheel_{w['name']}"
        wheels.append(wname)
        out.append(f'      <body name="{wname}" pos="{fmt(w.get("at", [0, 0, 0]))}">\n')
        out.append(f'        <joint name="{wname}" type="hinge" axis="{fmt(a)}"/>\n')
        inertial({"mass": w.get("mass", 0.0), "inertia": i3}, "        ")
        out.append("      </body>\n")
    for j in children.get(root, []):
        body_xml(j, "      ")
    out.append("    </body>\n  </worldbody>\n</mujoco>\n")
    return "".join(out), names, wheels


def initial_state(mj, m, d, scene_path):
    """Sets MuJoCo's qpos/qvel to the scene's [initial] state (satsim conventions: body
    angular velocity, base at rest at the origin)."""
    scene, model = load(scene_path)
    ini = scene.get("initial", {})
    base = ini.get("base", {})
    hinges = ini.get("hinges", {})
    names = [h["name"] for h in model.get("hinge", [])]
    d.qpos[:] = 0.0
    d.qvel[:] = 0.0
    d.qpos[3:7] = base.get("attitude", [1.0, 0.0, 0.0, 0.0])
    d.qpos[0:3] = base.get("position", [0.0, 0.0, 0.0])
    if any(x != 0.0 for x in base.get("velocity", [0.0, 0.0, 0.0])):
        raise SceneError("a moving base origin is not written (satsim: body axes, MuJoCo: world)")
    d.qvel[3:6] = base.get("angular_velocity", [0.0, 0.0, 0.0])  # body frame
    for i, n in enumerate(names):
        j = m.joint(n)
        d.qpos[j.qposadr[0]] = hinges.get("angle", [0.0] * len(names))[i]
        d.qvel[j.dofadr[0]] = hinges.get("rate", [0.0] * len(names))[i]
    for w in scene.get("effects", {}).get("reaction_wheels", {}).get("wheel", []):
        j = m.joint(f"wheel_{w['name']}")
        d.qvel[j.dofadr[0]] = w.get("speed", 0.0)
    mj.mj_forward(m, d)


if __name__ == "__main__":
    print(write(sys.argv[1])[0], end="")
