"""`layered-swim export` (and run/follow --export): each file read back by a reader that is not
its writer, its joint tree, frame count and rate checked, and every segment's centre of mass,
by forward kinematics from the file's own local transforms, against the log within 1 mm."""
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from layered_swim.body.model import load_body
from layered_swim.config import ConfigError
from layered_swim.export.target import check_target
from layered_swim.recorder import SPOOL_DIR, read_log

REPO = Path(__file__).resolve().parents[1]
TOLERANCE_M = 1e-3
SECONDS = 2                       # 119 log rows at 60 Hz from t = 1/60 s: 60 frames at 30 fps
FRAMES_AT_30 = 60
BODY = load_body()
NAMES = BODY.segment_names
PARENTS = tuple(None if p is None else NAMES.index(p) for p in BODY.parents)
# z up (the log's) to y up (BVH's and glTF's): x stays, y becomes -z, z becomes y.
Z_TO_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def cli(*args, cwd=REPO):
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-m", "layered_swim", *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def assert_refused(result, *words):
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert "Traceback" not in result.stderr and len(lines) == 1, result.stderr
    assert all(word in lines[0] for word in words), lines[0]


@pytest.fixture(scope="module")
def swim(tmp_path_factory):
    """A 2 s front crawl, its .glb written by `run --export`, the other two by `export` (the .usda
    over an older file, with --overwrite)."""
    folder = tmp_path_factory.mktemp("export")
    run = folder / "run"
    result = cli("run", "--stroke", "front_crawl", "--seconds", SECONDS, "--out", run, "--export", folder / "swim.glb",
                 "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["exported_to"] == str(folder / "swim.glb")
    (folder / "swim.usda").write_text("an older file")
    for name, extra in (("swim.bvh", ()), ("swim.usda", ("--overwrite",))):
        result = cli("export", run, "--to", folder / name, *extra)
        assert result.returncode == 0, result.stderr
        assert f"wrote {FRAMES_AT_30} frames at 30 fps of 16 segments" in result.stdout
    return folder, read_log(run)


def log_com_m(log, frame: int) -> np.ndarray:
    """The log's centres of mass (S, 3) at a 30 fps frame: frame k is log row 2 k."""
    return log["segment_pos_m"][2 * frame]


def segment_com_m(origin_m: np.ndarray, rotation: list, center_m: np.ndarray) -> np.ndarray:
    """Centres of mass (S, 3) from link origins (S, 3), rotations (S, 3x3) and centres in the link frames."""
    return np.array([o + r @ c for o, r, c in zip(origin_m, rotation, center_m)])


def forward_kinematics(names, parents, translation_m, rotation):
    """World origins and rotation matrices of a tree from its local ones (parents before children)."""
    origin, world = {}, {}
    for name, parent in zip(names, parents):
        if parent is None:
            origin[name], world[name] = translation_m[name], rotation[name]
        else:
            origin[name] = origin[parent] + world[parent] @ translation_m[name]
            world[name] = world[parent] @ rotation[name]
    return origin, world


def axis_matrix(axis: str, deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    i = "XYZ".index(axis)
    j, k = (i + 1) % 3, (i + 2) % 3
    m = np.eye(3)
    m[j, j], m[j, k], m[k, j], m[k, k] = c, -s, s, c
    return m


# ---------------------------------------------------------------- BVH


def test_bvh_reads_back_with_the_swim(swim):
    import bvh
    with warnings.catch_warnings():       # bvhio's `import glm`, a name PyGLM is deprecating
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        import bvhio

    folder, log = swim
    path = folder / "swim.bvh"
    strict = bvhio.readAsBvh(str(path))       # a strict parser: the syntax is right
    assert strict.FrameCount == FRAMES_AT_30
    mocap = bvh.Bvh(path.read_text())
    assert mocap.nframes == len(mocap.frames) == FRAMES_AT_30
    assert mocap.frame_time == pytest.approx(1 / 30, abs=1e-9)
    names = mocap.get_joints_names()
    assert sorted(names) == sorted(NAMES)
    parents = {name: mocap.joint_parent(name) for name in names}
    assert {n: None if p is None else p.name for n, p in parents.items()} == dict(zip(NAMES, BODY.parents))
    tree_parents = [None if parents[n] is None else parents[n].name for n in names]
    center = {name: Z_TO_Y @ BODY.center_m[NAMES.index(name)] for name in names}
    worst = 0.0
    for k in range(FRAMES_AT_30):
        translation, rotation = {}, {}
        for name in names:
            channels = mocap.joint_channels(name)
            values = mocap.frame_joint_channels(k, name, channels)
            offset = np.array(mocap.joint_offset(name))
            positions = [v for c, v in zip(channels, values) if c.endswith("position")]
            translation[name] = offset + (np.array(positions) if positions else 0.0)
            rotation[name] = np.eye(3)
            for c, v in zip(channels, values):
                if c.endswith("rotation"):
                    rotation[name] = rotation[name] @ axis_matrix(c[0], v)
        origin, world = forward_kinematics(names, tree_parents, translation, rotation)
        com_y = segment_com_m([origin[n] for n in NAMES], [world[n] for n in NAMES], [center[n] for n in NAMES])
        worst = max(worst, np.abs(com_y @ Z_TO_Y - log_com_m(log, k)).max())
    print(f"bvh: max centre-of-mass error {worst * 1000:.4f} mm")
    assert worst < TOLERANCE_M


# ---------------------------------------------------------------- glTF


def gltf_arrays(gltf, index: int) -> np.ndarray:
    """An accessor's values, read from the GLB's binary chunk."""
    accessor = gltf.model.accessors[index]
    view = gltf.model.bufferViews[accessor.bufferView]
    dtype = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}[accessor.componentType]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[accessor.type]
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    data = gltf.get_glb_resource().data
    return np.frombuffer(data, dtype, accessor.count * width, start).reshape(accessor.count, width)


def test_glb_reads_back_with_the_swim(swim):
    gltflib = pytest.importorskip("gltflib")
    trimesh = pytest.importorskip("trimesh")

    folder, log = swim
    gltf = gltflib.GLTF.load_glb(str(folder / "swim.glb"))
    nodes = gltf.model.nodes
    by_name = {node.name: i for i, node in enumerate(nodes)}
    assert set(NAMES) <= set(by_name) and len(nodes) == 32
    parent_of = {nodes[c].name: node.name for node in nodes for c in node.children or []}
    assert {n: parent_of.get(n) for n in NAMES} == dict(zip(NAMES, BODY.parents))
    assert all(parent_of[f"{n}_box"] == n and nodes[by_name[f"{n}_box"]].mesh is not None for n in NAMES)
    (animation,) = gltf.model.animations
    times = {sampler.input for sampler in animation.samplers}
    assert len(times) == 1
    times_s = gltf_arrays(gltf, times.pop())[:, 0]
    assert len(times_s) == FRAMES_AT_30 and np.allclose(np.diff(times_s), 1 / 30, atol=1e-6)
    animated = {(nodes[c.target.node].name, c.target.path): gltf_arrays(gltf, animation.samplers[c.sampler].output)
                for c in animation.channels}
    assert set(animated) == {("pelvis", "translation")} | {(n, "rotation") for n in NAMES}
    names = NAMES + tuple(f"{n}_box" for n in NAMES)
    worst = 0.0
    for k in range(FRAMES_AT_30):
        translation, rotation = {}, {}
        for name in names:
            node = nodes[by_name[name]]
            moved, turned = animated.get((name, "translation")), animated.get((name, "rotation"))
            translation[name] = np.asarray(node.translation if moved is None else moved[k], dtype=float)
            quat = (node.rotation or [0, 0, 0, 1]) if turned is None else turned[k]
            rotation[name] = Rotation.from_quat(np.asarray(quat, dtype=float)).as_matrix()
        origin, _ = forward_kinematics(names, [parent_of.get(n) for n in names], translation, rotation)
        com_y = np.array([origin[f"{n}_box"] for n in NAMES])
        worst = max(worst, np.abs(com_y @ Z_TO_Y - log_com_m(log, k)).max())
    print(f"glb: max centre-of-mass error {worst * 1000:.4f} mm")
    assert worst < TOLERANCE_M
    # A second reader: trimesh places the 16 boxes where frame 0 has them.
    scene = trimesh.load(str(folder / "swim.glb"))
    assert len(scene.geometry) == 16
    placed = np.array([scene.graph.get(frame_to=f"{n}_box")[0][:3, 3] for n in NAMES])
    assert np.abs(placed @ Z_TO_Y - log_com_m(log, 0)).max() < TOLERANCE_M


# ---------------------------------------------------------------- USD


def test_usda_reads_back_with_the_swim(swim):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    folder, log = swim
    stage = Usd.Stage.Open(str(folder / "swim.usda"))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == 30
    assert stage.GetEndTimeCode() - stage.GetStartTimeCode() + 1 == FRAMES_AT_30
    prims = {p.GetName(): p for p in stage.Traverse() if p.IsA(UsdGeom.Xform) and p.GetName() != "swimmer"}
    assert set(prims) == set(NAMES)
    parents = {n: p.GetParent().GetName() for n, p in prims.items()}
    assert {n: None if p == "swimmer" else p for n, p in parents.items()} == dict(zip(NAMES, BODY.parents))
    pelvis = UsdGeom.Xformable(prims["pelvis"])
    assert len(pelvis.GetOrderedXformOps()[0].GetTimeSamples()) == FRAMES_AT_30
    names = NAMES + tuple(f"{n}_box" for n in NAMES)
    tree = [None if parents[n] == "swimmer" else parents[n] for n in NAMES] + list(NAMES)
    worst = 0.0
    for k in range(FRAMES_AT_30):
        translation, rotation = {}, {}
        for name in NAMES:
            for prim, key in ((prims[name], name), (prims[name].GetChild(f"{name}_box"), f"{name}_box")):
                # USD's matrices act on row vectors: the transpose of ours.
                matrix = np.array(UsdGeom.Xformable(prim).GetLocalTransformation(Usd.TimeCode(k))).T
                translation[key], rotation[key] = matrix[:3, 3], matrix[:3, :3]
        origin, _ = forward_kinematics(names, tree, translation, rotation)
        com = np.array([origin[f"{n}_box"] for n in NAMES])
        worst = max(worst, np.abs(com - log_com_m(log, k)).max())
    print(f"usda: max centre-of-mass error {worst * 1000:.4f} mm")
    assert worst < TOLERANCE_M


# ---------------------------------------------------------------- partial runs, rates, refusals


def test_a_stopped_run_exports_what_it_logged_at_any_rate(swim, tmp_path):
    """A killed run leaves log.partial/ (and here no config.json: the packaged body); --fps 24."""
    import bvh

    _, log = swim
    stopped = tmp_path / "stopped"
    (stopped / SPOOL_DIR).mkdir(parents=True)
    rows = 100
    np.savez(stopped / SPOOL_DIR / "chunk-000000.npz", **{k: v[:rows] for k, v in log.items()
                                                          if isinstance(v, np.ndarray) and v.dtype.kind == "f"})
    names = {k: log[k].tolist() for k in ("segment_names", "joint_names", "pose_names")}
    (stopped / SPOOL_DIR / "names.json").write_text(json.dumps(names))
    result = cli("export", stopped, "--to", tmp_path / "stopped.bvh", "--fps", 24)
    assert result.returncode == 0, result.stderr
    frames = int((rows - 1) / 60 * 24) + 1        # 1/60 s to 100/60 s at 1/24 s
    assert f"wrote {frames} frames at 24 fps" in result.stdout and "stopped" in result.stdout
    mocap = bvh.Bvh((tmp_path / "stopped.bvh").read_text())
    assert mocap.nframes == len(mocap.frames) == frames
    assert mocap.frame_time == pytest.approx(1 / 24, abs=1e-9)


def test_follow_exports_the_folder_it_wrote(tmp_path):
    result = cli("follow", "figure_eight", "--seconds", 1, "--out", tmp_path / "eight", "--export",
                 tmp_path / "eight.usda", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["exported_to"] == str(tmp_path / "eight.usda")
    assert "endTimeCode = 29" in (tmp_path / "eight.usda").read_text()


def test_refused_in_one_line(swim, tmp_path):
    folder, _ = swim
    assert_refused(cli("export", tmp_path, "--to", tmp_path / "x.bvh"), "no log.npz")
    assert not (tmp_path / "x.bvh").exists()
    kept = tmp_path / "kept.bvh"
    kept.write_text("someone's file")
    assert_refused(cli("export", folder / "run", "--to", kept), "exists", "--overwrite")
    assert_refused(cli("run", "--stroke", "rest", "--seconds", 1, "--out", tmp_path / "r", "--export", kept),
                   "exists", "--overwrite")
    assert kept.read_text() == "someone's file" and not (tmp_path / "r").exists()
    for bad, words in ((tmp_path / "swim.fbx", ("format", ".bvh, .glb, .usda")),
                       (tmp_path / "swim", ("no suffix",)),
                       (tmp_path / "nowhere" / "swim.glb", ("no such folder",)),
                       (folder / "run", ("format",))):
        with pytest.raises(ConfigError, match=words[0]):
            check_target(bad)
    (tmp_path / "folder.bvh").mkdir()
    with pytest.raises(ConfigError, match="not a file"):
        check_target(tmp_path / "folder.bvh", overwrite=True)
    link = tmp_path / "link.glb"
    link.symlink_to(kept)
    dangling = tmp_path / "dangling.usda"
    dangling.symlink_to(tmp_path / "missing.usda")
    for path in (link, dangling):
        with pytest.raises(ConfigError, match="symbolic link"):
            check_target(path, overwrite=True)


# ---------------------------------------------------------------- Blender's own importers (slow)

BLENDER_SCRIPT = """
import bpy, json, sys
bvh_path, glb_path, usda_path, frames, out = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
result = {}
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
bpy.ops.import_anim.bvh(filepath=bvh_path, global_scale=1.0, axis_forward="-Z", axis_up="Y",
                        update_scene_fps=True, update_scene_duration=True)
armature = next(o for o in scene.objects if o.type == "ARMATURE")
result["bvh_fps"] = scene.render.fps / scene.render.fps_base
result["bvh_parents"] = {b.name: b.parent.name if b.parent else None for b in armature.data.bones}
result["bvh_heads"], result["bvh_tails"] = [], []
for k in range(frames):
    scene.frame_set(1 + k)                 # the BVH's frame 0 lands on Blender's frame 1
    bones = armature.pose.bones
    result["bvh_heads"].append({b.name: list(armature.matrix_world @ b.head) for b in bones})
    result["bvh_tails"].append({b.name: list(armature.matrix_world @ b.tail) for b in bones})
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps = 30
bpy.ops.import_scene.gltf(filepath=glb_path)
result["glb_parents"] = {o.name: o.parent.name if o.parent else None for o in scene.objects}
result["glb_boxes"] = []
for k in range(frames):
    scene.frame_set(k)                     # glTF time k / 30 s is frame k at 30 fps
    result["glb_boxes"].append({o.name: list(o.matrix_world.translation) for o in scene.objects})
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
bpy.ops.wm.usd_import(filepath=usda_path)
result["usda_range"] = [scene.frame_start, scene.frame_end]
result["usda_boxes"] = []
for k in range(frames):
    scene.frame_set(k)                     # time code k is frame k
    result["usda_boxes"].append({o.name: list(o.matrix_world.translation) for o in scene.objects})
json.dump(result, open(out, "w"))
"""


def blender_python() -> str | None:
    """A Python that imports bpy (Blender as a module, `pip install bpy`, in a venv of its own):
    $BLENDER_PYTHON, else none."""
    python = os.environ.get("BLENDER_PYTHON")
    if not python:
        return None
    probe = subprocess.run([python, "-c", "import bpy"], capture_output=True, timeout=120)
    return python if probe.returncode == 0 else None


@pytest.mark.slow
def test_blender_imports_each_format_where_the_swim_was(swim, tmp_path):
    python = blender_python()
    if python is None:
        pytest.skip("no Python with bpy: set BLENDER_PYTHON to one (pip install bpy in a venv of its own)")
    folder, log = swim
    out = tmp_path / "blender.json"
    result = subprocess.run([python, "-c", BLENDER_SCRIPT, *(folder / f"swim.{f}" for f in ("bvh", "glb", "usda")),
                             str(FRAMES_AT_30), out], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    seen = json.loads(out.read_text())
    assert seen["bvh_fps"] == pytest.approx(30)
    assert seen["bvh_parents"] == dict(zip(NAMES, BODY.parents))
    assert {n: seen["glb_parents"][n] for n in NAMES} == dict(zip(NAMES, BODY.parents))
    rotation = Rotation.from_quat(log["segment_quat_xyzw"].reshape(-1, 4))
    shape = log["segment_pos_m"].shape
    center = np.tile(BODY.center_m, (shape[0], 1))
    origin = log["segment_pos_m"] - rotation.apply(center).reshape(shape)     # the joints
    end = origin + rotation.apply(2 * center).reshape(shape)                  # the leaves' End Sites
    leaves = [n for n in NAMES if n not in BODY.parents]
    assert seen["usda_range"] == [0, FRAMES_AT_30 - 1]
    worst = {"bvh": 0.0, "glb": 0.0, "usda": 0.0}
    for k in range(FRAMES_AT_30):
        heads = np.array([seen["bvh_heads"][k][n] for n in NAMES])
        tails = np.array([seen["bvh_tails"][k][n] for n in leaves])
        boxes = {f: np.array([seen[f"{f}_boxes"][k][f"{n}_box"] for n in NAMES]) for f in ("glb", "usda")}
        worst["bvh"] = max(worst["bvh"], np.abs(heads - origin[2 * k]).max(),
                           np.abs(tails - end[2 * k][[NAMES.index(n) for n in leaves]]).max())
        for f in ("glb", "usda"):
            worst[f] = max(worst[f], np.abs(boxes[f] - log_com_m(log, k)).max())
    print("Blender: max error " + ", ".join(f"{f} {e * 1000:.4f} mm" for f, e in worst.items()))
    assert max(worst.values()) < TOLERANCE_M
