"""The Python module against the C++ library and command line (run by ctest: docs/python.md)."""
import json
import os
import resource
import subprocess

import numpy as np
import pytest

import peelcd

FIXTURES = os.environ.get("PEELCD_FIXTURES", os.path.join(os.path.dirname(__file__), "..", "..", "fixtures"))
PEELCD = os.environ.get("PEELCD_BIN", "peelcd")
BACKEND = "osmesa"  # as the command line's default


def cli_json(scene, *args):
    out = subprocess.run([PEELCD, "detect", scene, "--json", "-", "--quiet", "--backend", BACKEND, *args],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def same_pairs(py_result, cli):
    """Python's pairs equal the command line's JSON: objects, triangle pairs, kinds, relation."""
    assert len(py_result["pairs"]) == len(cli["pairs"])
    for p, c in zip(py_result["pairs"], cli["pairs"]):
        assert (p["a"], p["b"]) == (c["object_a"], c["object_b"])
        assert p["colliding"].tolist() == [[x["tri_a"], x["tri_b"]] for x in c["colliding"]]  # one name
        assert p["triangles"] is p["colliding"]  # the 0.2 name, kept for 0.3
        assert p["kinds"] == [x["kind"] for x in c["colliding"]]
        assert p["relation"] == c["relation"]
        assert p["is_collision"] == c["is_collision"]
        segs = np.array([x["segment"] for x in c["colliding"]]).reshape(-1, 2, 3)
        assert np.allclose(p["segments"], segs, rtol=1e-12, atol=1e-12)


def test_default_scene_equals_the_command_line():
    scene = os.path.join(FIXTURES, "scenes", "bunny_dragon.json")
    objects = peelcd.load_scene(scene)
    result = peelcd.Detector(BACKEND).detect(objects)
    same_pairs(result, cli_json(scene))
    assert result["pairs"][0]["triangles"].shape == (228, 2)


def write_obj(path, mesh):
    with open(path, "w") as f:
        for v in mesh.V:
            f.write("v %r %r %r\n" % tuple(float(x) for x in v))
        for t in mesh.F:
            f.write("f %d %d %d\n" % tuple(int(i) + 1 for i in t))


@pytest.mark.parametrize("name,objects", peelcd.classes(), ids=[n for n, _ in peelcd.classes()])
def test_every_class_equals_the_command_line(tmp_path, name, objects):
    # The class's meshes as files and a scene; both sides load them through the same loader.
    scene = {"objects": []}
    for i, o in enumerate(objects):
        path = tmp_path / ("m%d.obj" % i)
        write_obj(path, o["mesh"])
        scene["objects"].append({"name": "o%d" % i, "mesh": path.name, "self": o["self"]})
    scene_path = tmp_path / "scene.json"
    scene_path.write_text(json.dumps(scene))
    loaded = peelcd.load_scene(str(scene_path))
    result = peelcd.Detector(BACKEND).detect(loaded)
    same_pairs(result, cli_json(str(scene_path)))


def test_world_equals_the_frame_api_and_the_exact_reference():
    objects = peelcd.load_scene(os.path.join(FIXTURES, "scenes", "bunny_dragon.json"))
    world = peelcd.World()
    for o in objects:
        world.add_rigid(o["mesh"], name=o["name"])
    pairs = world.collide()["pairs"]
    exact = peelcd.exact_pairs(objects[0]["mesh"], objects[1]["mesh"])
    assert pairs[0]["triangles"].tolist() == exact.tolist()


def test_containment_and_volume():
    ball = peelcd.load_mesh(os.path.join(FIXTURES, "meshes", "generated", "sphere_24x48.obj"))
    small = peelcd.Mesh(ball.V * 0.3 + np.array([0.1, 0.0, 0.0]), ball.F)
    p = peelcd.collide(small, ball, volume=True)
    assert p["relation"] == "a_inside_b" and p["is_collision"] and len(p["triangles"]) == 0
    assert abs(p["volume"] - 0.027 * 4.18) < 0.01  # about (0.3)^3 of the faceted unit ball's volume


def test_depth_separates_and_swaps():
    ball = peelcd.load_mesh(os.path.join(FIXTURES, "meshes", "generated", "sphere_24x48.obj"))
    other = peelcd.Mesh(ball.V * 0.8 + np.array([0.5, 0.2, 0.0]), ball.F)
    p = peelcd.collide(ball, other, depth=True)
    assert p["relation"] == "crossing"
    n, d = p["depth_direction"], p["depth"]
    assert abs(np.linalg.norm(n) - 1.0) < 1e-12 and 1.0 < d < 1.5  # 1.8 - |(0.5, 0.2)|, faceted
    moved = peelcd.Mesh(ball.V + (d + 1e-6) * n, ball.F)
    assert not peelcd.collide(moved, other)["is_collision"]
    q = peelcd.collide(other, ball, depth=True)  # swapped: (-n, d)
    assert abs(q["depth"] - d) < 1e-9 * d and np.allclose(q["depth_direction"], -n, atol=1e-9)
    open_mesh = peelcd.Mesh(ball.V, ball.F[:-1])
    assert peelcd.collide(open_mesh, other, depth=True)["depth"] is None


def bad(fn, kind, words):
    with pytest.raises(kind) as e:
        fn()
    assert words in str(e.value)


def test_bad_inputs_raise_clear_errors():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    F = np.array([[0, 1, 2]])
    bad(lambda: peelcd.Mesh(V.astype(np.float32), F), TypeError, "dtype must be float64")
    bad(lambda: peelcd.Mesh(V[:, :2].copy(), F), ValueError, "shape must be (n, 3)")
    bad(lambda: peelcd.Mesh(V, F.astype(np.float64)), TypeError, "dtype must be an integer type")
    bad(lambda: peelcd.Mesh(V, np.array([[0, 1, 3]])), ValueError, "uses vertex 3 but there are 3 vertices")
    bad(lambda: peelcd.Mesh(V, np.array([[0, 1, -1]])), ValueError, "uses vertex -1")
    nan = V.copy()
    nan[2, 1] = np.nan
    bad(lambda: peelcd.Mesh(nan, F), ValueError, "vertex 2 has a NaN")
    bad(lambda: peelcd.Mesh(np.zeros((6, 3))[::2], F), ValueError, "must be C-contiguous")
    bad(lambda: peelcd.Mesh(V, np.zeros((0, 3), dtype=np.int32)), ValueError, "at least one triangle")
    bad(lambda: peelcd.load_mesh("/nonexistent.obj"), ValueError, "/nonexistent.obj")
    world = peelcd.World()
    body = world.add_deforming(peelcd.Mesh(V, F))
    bad(lambda: world.set_vertices(body, np.zeros((4, 3))), ValueError, "has 3 vertices, given 4")
    bad(lambda: world.set_pose(body, np.eye(4)), ValueError, "is deforming")
    bad(lambda: world.set_pose(99, np.eye(4)), ValueError, "no body 99")
    bad(lambda: world.add_rigid(peelcd.Mesh(V, F), pose=np.zeros((4, 4))), ValueError, "last row")
    bad(lambda: world.collide(views=4), ValueError, "option 'views': must be 1, 2 or 3")
    bad(lambda: world.collide(stage="fancy"), ValueError, "unknown stage \"fancy\"")
    bad(lambda: world.collide(colour=1), TypeError, "unknown option 'colour'")
    bad(lambda: peelcd.World("vulkan"), ValueError, "vulkan")


def rss_kb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def test_no_leak_over_ten_thousand_frames_of_a_deforming_loop():
    ball = peelcd.load_mesh(os.path.join(FIXTURES, "meshes", "generated", "ball_16x32.obj"))
    world = peelcd.World()
    a = world.add_deforming(ball)
    b = world.add_rigid(ball, pose=np.diag([1.0, 1.0, 1.0, 1.0]))
    V0 = ball.V
    def frames(n, start):
        for f in range(start, start + n):
            V = V0 * (1.0 + 0.01 * np.sin(0.1 * f)) + np.array([1.2, 0.0, 0.0])
            world.set_vertices(a, V)
            r = world.collide()
            assert r["is_collision"]
    frames(1000, 0)  # warm: every buffer at its size
    before = rss_kb()
    frames(9000, 1000)
    grown = rss_kb() - before
    print("RSS grew by %d KB over 9,000 frames" % grown)
    assert grown < 2048


def uv_sphere(center, radius, n=24):
    """A closed UV sphere of 2 n^2 triangles."""
    th = np.linspace(0, np.pi, n + 1)[:, None]
    ph = np.linspace(0, 2 * np.pi, n, endpoint=False)[None, :]
    V = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th) + 0 * ph], -1).reshape(-1, 3)
    F = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * n + j, i * n + (j + 1) % n, (i + 1) * n + j, (i + 1) * n + (j + 1) % n
            F += [[a, c, b], [b, c, d]]
    return peelcd.Mesh(V * radius + np.asarray(center, float), np.array(F, np.int64))


def test_gl_options_as_keywords_recorded_in_the_result():
    a, b = uv_sphere((0, 0, 0), 1.0), uv_sphere((1.2, 0.1, 0.05), 1.0)
    assert peelcd.gl_options() == {"peeler": "abuffer", "resolve": "auto", "batch": True, "gpu_select": True,
                                   "gpu_filter": True, "coverage": "auto"}
    world = peelcd.World(BACKEND, peeler="multipass", resolve="host", batch=False, gpu_select=False, gpu_filter=False,
                         coverage="compute")
    world.add_rigid(a)
    world.add_rigid(b)
    r = world.collide(stage="image")
    assert r["gl_options"] == {"peeler": "multipass", "resolve": "host", "batch": False, "gpu_select": False,
                               "gpu_filter": False, "coverage": "compute"}
    exact = peelcd.exact_pairs(a, b).tolist()
    assert r["pairs"][0]["triangles"].tolist() == exact
    d = peelcd.Detector(BACKEND, resolve="gpu").detect([a, b], stage="image")
    assert d["gl_options"]["resolve"] == "gpu" and d["pairs"][0]["triangles"].tolist() == exact
    assert peelcd.collide(a, b, backend=BACKEND, batch=False, stage="image")["triangles"].tolist() == exact
    assert "gl_options" not in peelcd.World().collide()
    with pytest.raises(ValueError, match="peeler"):
        peelcd.World(BACKEND, peeler="fast")
    with pytest.raises(TypeError, match="unknown GL option"):
        peelcd.World(BACKEND, colour=True)
    with pytest.raises(ValueError, match="no GL stage"):
        peelcd.World("cpu", batch=False)


def test_osmesa_and_egl_worlds_in_turn_give_each_ones_pairs():
    """Mesa's OSMesa and EGL share one GL dispatch: each World must reach its own context."""
    a, b = uv_sphere((0, 0, 0), 1.0), uv_sphere((1.2, 0.1, 0.05), 1.0)
    exact = peelcd.exact_pairs(a, b).tolist()
    for views in ((3, 1), (1, 3)):
        worlds = []
        for backend in ("egl", "osmesa"):
            w = peelcd.World(backend)
            w.add_rigid(a)
            w.add_rigid(b)
            worlds.append(w)
        for frame in range(4):
            for w, v in zip(worlds, views):
                assert w.collide(stage="image", views=v)["pairs"][0]["triangles"].tolist() == exact


def test_threads_each_with_its_own_world_and_detector_finish_with_the_right_pairs():
    """Several threads' first frames at once (each its own World, Detector or collide): no hang."""
    import threading
    a, b = uv_sphere((0, 0, 0), 1.0, 16), uv_sphere((1.2, 0.1, 0.05), 1.0, 16)
    exact = peelcd.exact_pairs(a, b).tolist()
    results, errors = {}, []

    def run(k):
        try:
            if k % 3 == 0:
                w = peelcd.World()
                w.add_rigid(a)
                w.add_rigid(b)
                got = [w.collide()["pairs"][0]["triangles"].tolist() for _ in range(3)]
            elif k % 3 == 1:
                d = peelcd.Detector("cpu")
                got = [d.detect([a, b])["pairs"][0]["triangles"].tolist() for _ in range(3)]
            else:
                got = [peelcd.collide(a, b)["triangles"].tolist() for _ in range(3)]
            results[k] = got
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(repr(e))

    threads = [threading.Thread(target=run, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert not any(t.is_alive() for t in threads), "a thread hung"
    assert errors == []
    assert all(got == [exact] * 3 for got in results.values()) and len(results) == 6


def shared_world_run(threads, with_changes, frames=40, cap_s=60.0):
    """One World of the default scene shared by `threads` threads that call collide() (and, with
    `with_changes`, one more that calls set_pose / set_self with unchanged values), until `frames`
    frames completed and some call was refused (or `cap_s` seconds passed): the number of exact
    pairs, the counts of completed frames with the exact pairs, with other pairs, the refusals
    and any other exception."""
    import threading
    import time
    objects = peelcd.load_scene(os.path.join(FIXTURES, "scenes", "bunny_dragon.json"))
    exact = peelcd.exact_pairs(objects[0]["mesh"], objects[1]["mesh"]).tolist()
    w = peelcd.World()
    ia = w.add_rigid(objects[0]["mesh"], name="bunny")
    w.add_rigid(objects[1]["mesh"], name="dragon")
    right, wrong, refused, other = [0], [], [], []
    lock = threading.Lock()
    stop = threading.Event()

    def note(kind, value=None):
        with lock:
            if kind == "right":
                right[0] += 1
            else:
                {"wrong": wrong, "refused": refused, "other": other}[kind].append(value)

    def collide_loop():
        while not stop.is_set():
            try:
                got = w.collide()["pairs"]
                tris = got[0]["triangles"].tolist() if got else []
                note("right") if tris == exact else note("wrong", len(tris))
            except RuntimeError as e:
                note("refused", str(e))
            except Exception as e:  # noqa: BLE001 - reported below
                note("other", repr(e))

    def change_loop():
        while not stop.is_set():
            try:
                w.set_pose(ia, np.eye(4))  # the same pose: every frame's pairs stay the exact ones
                w.set_self("bunny", False)
            except RuntimeError as e:
                note("refused", str(e))
            except Exception as e:  # noqa: BLE001
                note("other", repr(e))

    ts = [threading.Thread(target=collide_loop) for _ in range(threads)]
    if with_changes:
        ts.append(threading.Thread(target=change_loop))
    for t in ts:
        t.start()
    start = time.monotonic()
    while time.monotonic() - start < cap_s:
        with lock:
            if right[0] + len(wrong) >= frames and refused:
                break
        time.sleep(0.01)
    stop.set()
    for t in ts:
        t.join(timeout=300)
    assert not any(t.is_alive() for t in ts), "a thread hung"
    assert w.collide()["pairs"][0]["triangles"].tolist() == exact  # the World is intact
    return len(exact), right[0], wrong, refused, other


@pytest.mark.parametrize("threads,with_changes", [(2, False), (4, False), (2, True)])
def test_one_world_shared_by_threads_refuses_the_second_and_every_frame_is_right(threads, with_changes):
    """A World used from several threads at once: the second thread gets the documented
    RuntimeError (at least one per run: the threads start together and a frame releases the GIL
    while it runs), and every frame that completed has the exact pairs (228 on the default scene)."""
    n, right, wrong, refused, other = shared_world_run(threads, with_changes)
    assert n == 228
    assert wrong == [] and other == []
    assert right >= 1
    assert len(refused) >= 1, "no call was refused: the threads never overlapped, or the guard is missing"
    assert all("peelcd::World: called from a second thread" in r for r in refused)


def test_every_option_is_a_keyword_of_every_entry_self_included():
    """Every key of peelcd.options() passed by keyword (at its default, and self=True) to
    World.collide, Detector.detect and peelcd.collide: no clash with the bound instance."""
    a, b = uv_sphere((0, 0, 0), 1.0, 12), uv_sphere((1.2, 0.1, 0.05), 1.0, 12)
    exact = peelcd.exact_pairs(a, b).tolist()
    options = peelcd.options()
    assert "self" in options
    for key, default in options.items():
        w = peelcd.World()
        w.add_rigid(a)
        w.add_rigid(b)
        assert isinstance(w.collide(**{key: default}), peelcd.Result), key
        assert isinstance(peelcd.Detector("cpu").detect([a, b], **{key: default}), peelcd.Result), key
        assert isinstance(peelcd.collide(a, b, **{key: default}), peelcd.PairResult), key
    w = peelcd.World()
    w.add_rigid(a)
    w.add_rigid(b)
    r = w.collide(stage="exact", self=True)
    assert [(p["a"], p["b"]) for p in r["pairs"]] == [(0, 0), (0, 1), (1, 1)]
    assert r["pairs"][1]["triangles"].tolist() == exact
    d = peelcd.Detector("cpu").detect([a, b], self=True)
    assert d["pairs"][1]["triangles"].tolist() == exact
    assert peelcd.Detector("cpu").detect(objects=[a, b], self=True)["pairs"][1]["triangles"].tolist() == exact
    assert peelcd.collide(a, b, self=True)["triangles"].tolist() == exact


def test_collide_always_returns_a_result():
    a = uv_sphere((0, 0, 0), 1.0, 12)
    far = peelcd.collide(a, uv_sphere((9, 0, 0), 1.0, 12))
    assert isinstance(far, peelcd.PairResult) and not far
    assert far["is_collision"] is False and far["relation"] == "disjoint" and far["colliding"].shape == (0, 2)
    near = peelcd.collide(a, uv_sphere((1.2, 0.1, 0.05), 1.0, 12))
    assert set(near) <= set(far) | {"segments", "volume_unknown", "depth_unknown"}  # the same keys where it matters


def test_bodies_by_name_and_names_unique():
    a, b = uv_sphere((0, 0, 0), 1.0, 12), uv_sphere((1.2, 0.1, 0.05), 1.0, 12)
    w = peelcd.World()
    ia = w.add_rigid(a, name="a")
    w.add_rigid(b, name="b")
    with pytest.raises(ValueError, match="the name is taken by body 0"):
        w.add_rigid(b, name="a")
    assert w.find("a") == ia and w.find("nobody") is None and len(w) == 2
    far = np.eye(4)
    far[0, 3] = 9.0
    w.set_pose("a", far)
    assert not w.collide()
    w.set_pose(ia, np.eye(4))
    assert w.collide()
    with pytest.raises(ValueError, match="body 'c': no body has this name"):
        w.set_pose("c", np.eye(4))
    w.remove("a")
    assert w.find("a") is None
    w.add_rigid(a, name="a")  # the name is free again


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def posed_mesh(m, pose):
    """The mesh's world vertices as the library computes pose * v (column by column, then the
    translation; no fused multiply-add), so the exact reference sees the World's very doubles."""
    L, t, V = pose[:3, :3], pose[:3, 3], m.V
    W = ((V[:, 0:1] * L[:, 0] + V[:, 1:2] * L[:, 1]) + V[:, 2:3] * L[:, 2]) + t
    return peelcd.Mesh(np.ascontiguousarray(W), m.F)


@pytest.mark.parametrize("condition", [1e10, 1e11, 1e12, 1e13, 1e14, 1e15])
def test_ill_conditioned_poses_are_exact(condition):
    """Two bodies sharing one rotated, anisotropically scaled pose (axis scales sqrt(c) and
    1/sqrt(c), determinant 1): the World's pairs equal the exact pairs of the world meshes, or the
    pose is refused; never fewer pairs in silence. Large bodies (over 8,192 triangles) too, which
    the World traverses through their poses when they are well conditioned."""
    for segments in (12, 70):
        a, b = uv_sphere((0, 0, 0), 1.0, segments), uv_sphere((1.2, 0.1, 0.05), 1.0, segments)
        pose = np.eye(4)
        pose[:3, :3] = rotation((1, 2, 3), 0.7) @ np.diag([np.sqrt(condition), 1.0, 1.0 / np.sqrt(condition)])
        w = peelcd.World()
        try:
            w.add_rigid(a, pose)
            w.add_rigid(b, pose)
        except ValueError as e:  # a refusal names the condition
            assert "condition" in str(e)
            continue
        wa, wb = posed_mesh(a, pose), posed_mesh(b, pose)
        exact = peelcd.exact_pairs(wa, wb).tolist()
        assert len(exact) > 0
        for frame in range(2):  # a first frame, then one that keeps what it can
            got = w.collide(stage="exact")["pairs"]
            assert got and got[0]["triangles"].tolist() == exact, (segments, frame)


@pytest.mark.parametrize("scale", [1e-110, 1e-300, 5e-320, 1e300])
def test_flat_touch_at_tiny_and_huge_scales(scale):
    """Two boxes meeting flat along an axis, all coordinates scaled: touching on every entry, no
    signal (the culling grid once divided 0 by 0 below ~1e-107)."""
    lo_a, hi_a = np.array([0.0, 0, 0]) * scale, np.array([1.0, 1, 1]) * scale
    lo_b, hi_b = np.array([1.0, 0.25, 0.25]) * scale, np.array([2.0, 0.75, 0.75]) * scale
    if scale < 1e-310:  # subnormal: the boxes' corners stay exact multiples of the unit
        lo_b, hi_b = np.array([1.0, 0.0, 0.0]) * scale, np.array([2.0, 1.0, 1.0]) * scale
    a, b = box(lo_a, hi_a), box(lo_b, hi_b)
    # Beyond float range a frame that may use the image stage is refused, naming it; the exact
    # path takes every finite double.
    options = {"stage": "exact"} if scale > 1e38 else {}
    if scale > 1e38:
        with pytest.raises(ValueError, match="outside the float range"):
            peelcd.collide(a, b)
    w = peelcd.World()
    w.add_rigid(a)
    w.add_rigid(b)
    r = w.collide(**options)
    assert [p["relation"] for p in r["pairs"]] == ["touching"]
    assert peelcd.collide(a, b, **options)["relation"] == "touching"
    assert [p["relation"] for p in peelcd.Detector("cpu").detect([a, b], **options)["pairs"]] == ["touching"]


def box(lo, hi):
    """A closed axis-aligned box of 12 triangles, outward normals."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    V = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], float)
    F = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], np.int64)
    return peelcd.Mesh(V, F)


def test_results_are_true_exactly_when_something_collides():
    a, b, far = uv_sphere((0, 0, 0), 1.0, 16), uv_sphere((1.2, 0.1, 0.05), 1.0, 16), uv_sphere((1.0, 1.0, 0), 0.35, 16)
    assert peelcd.collide(a, b)                      # crossing
    assert not peelcd.collide(a, uv_sphere((9, 0, 0), 1.0))  # boxes apart: a false result
    near = peelcd.collide(a, far)                    # boxes overlap, surfaces apart: a result that is false
    assert near is not None and not near and near["relation"] == "disjoint"
    inside = peelcd.collide(box((-0.2,) * 3, (0.2,) * 3), box((-1,) * 3, (1,) * 3))
    assert inside and len(inside["triangles"]) == 0 and inside["relation"] == "a_inside_b"
    w = peelcd.World()
    w.add_rigid(a)
    w.add_rigid(far)
    r = w.collide()
    assert isinstance(r, peelcd.Result) and not r and len(r["pairs"]) == 1
    assert peelcd.Detector().detect([a, b])


def test_max_contacts_one_is_a_first_contact_query():
    a, b = uv_sphere((0, 0, 0), 1.0, 24), uv_sphere((1.2, 0.1, 0.05), 1.0, 24)
    exact = {tuple(p) for p in peelcd.exact_pairs(a, b).tolist()}
    for stage in ("exact", "image"):
        first = peelcd.collide(a, b, stage=stage, max_contacts=1)
        assert first and len(first["triangles"]) == 1 and tuple(first["triangles"][0]) in exact
    assert len(peelcd.collide(a, b, max_contacts=0)["triangles"]) == len(exact)
    with pytest.raises(ValueError, match="max_contacts"):
        peelcd.collide(a, b, max_contacts=-1)


def test_contacts_pairs_gives_the_pairs_without_segments():
    a, b = uv_sphere((0, 0, 0), 1.0, 24), uv_sphere((1.2, 0.1, 0.05), 1.0, 24)
    for stage in ("exact", "image"):
        full = peelcd.collide(a, b, stage=stage)
        pairs = peelcd.collide(a, b, stage=stage, contacts="pairs")
        assert np.array_equal(full["colliding"], pairs["colliding"]) and pairs["relation"] == full["relation"]
        unclassified = np.array([k == "unclassified" for k in pairs["kinds"]])
        assert unclassified.any() and "crossing" in pairs["kinds"]
        assert np.isnan(pairs["segments"][unclassified]).all()
        assert not np.isnan(pairs["segments"][~unclassified]).any()
    with pytest.raises(ValueError, match="contacts"):
        peelcd.collide(a, b, contacts="segment")


def test_meshes_pickle_and_paths_may_be_pathlib():
    import copy
    import pathlib
    import pickle
    m = uv_sphere((0, 0, 0), 1.0, 8)
    for back in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        assert np.array_equal(back.V, m.V) and np.array_equal(back.F, m.F)
    path = pathlib.Path(FIXTURES) / "meshes" / "torus.obj"
    assert np.array_equal(peelcd.load_mesh(path).F, peelcd.load_mesh(str(path)).F)
    assert len(peelcd.load_scene(pathlib.Path(FIXTURES) / "scenes" / "bunny_dragon.json")) == 2


def test_rough_edges_names_ids_duck_typed_meshes_and_strict_objects():
    a, b = uv_sphere((0, 0, 0), 1.0, 16), uv_sphere((1.2, 0.1, 0.05), 1.0, 16)
    assert isinstance(peelcd.options()["threads"], int) and isinstance(peelcd.options()["slope"], float)
    w = peelcd.World()
    w.add_rigid(a, name="ball")
    w.add_rigid(b, name="other")
    p = w.collide()["pairs"][0]
    assert (p["name_a"], p["name_b"]) == ("ball", "other")
    with pytest.raises(ValueError, match="body -1: no such body"):
        w.set_pose(-1, np.eye(4))

    class Duck:  # what a trimesh.Trimesh offers
        vertices = a.V
        faces = a.F.astype(np.int64)
    exact = peelcd.exact_pairs(a, b).tolist()
    assert peelcd.collide(Duck(), b)["triangles"].tolist() == exact
    assert peelcd.exact_pairs(Duck(), b).tolist() == exact
    with pytest.raises(TypeError, match="expected a peelcd.Mesh or an object with .vertices and .faces"):
        peelcd.collide(42, b)
    # One mesh twice: against a copy of itself (every triangle meets its own copy); its self
    # pairs are exact_self_pairs.
    twice = peelcd.exact_pairs(a, a)
    assert len(twice) >= a.F.shape[0] and len(peelcd.exact_self_pairs(a)) != len(twice)
    d = peelcd.Detector()
    with pytest.raises(TypeError, match="objects\\[0\\]: unknown key 'colour'"):
        d.detect([{"mesh": a, "colour": 1}, b])
    with pytest.raises(ValueError, match="objects\\[1\\]: the name 'x' is taken"):
        d.detect([{"mesh": a, "name": "x"}, {"mesh": b, "name": "x"}])
    assert d.detect([{"mesh": a, "name": "p"}, {"mesh": b, "name": "q"}])["pairs"][0]["name_b"] == "q"


def test_gltf_scenes_load_as_the_command_line_takes_them():
    path = os.path.join(FIXTURES, "meshes", "three_box_nodes.gltf")
    objects = peelcd.load_scene(path)
    assert [o["name"] for o in objects] == ["left", "right", "far"]
    with pytest.raises(ValueError, match="glTF scene of 3 mesh nodes: peelcd.load_scene"):
        peelcd.load_mesh(path)


def test_a_margin_too_wide_for_the_image_stage_goes_to_the_exact_path():
    """A forced image stage with a margin of many texels (or one beyond float range) tests the
    pair on the exact path, says so, and gives the exact path's near pairs."""
    a, b = box((0, 0, 0), (1, 1, 1)), box((1.5, 0.2, 0.2), (2.5, 0.8, 0.8))
    for margin in (0.6, 1e160):
        exact = peelcd.collide(a, b, stage="exact", margin=margin)
        for backend in ("cpu", BACKEND):
            r = peelcd.collide(a, b, backend=backend, stage="image", margin=margin)  # a World
            d = peelcd.Detector(backend).detect([a, b], stage="image", margin=margin)["pairs"][0]
            for got in (r, d):
                assert got["margin_fallback"] and got["stage"] == "exact", (margin, backend)
                assert got["near_triangles"].tolist() == exact["near_triangles"].tolist()
    # A margin under an eighth of the ROI stays on the image stage.
    c = box((1.04, 0.2, 0.2), (2.04, 0.8, 0.8))
    r = peelcd.Detector("cpu").detect([a, c], stage="image", margin=0.05)["pairs"][0]
    assert not r["margin_fallback"] and r["stage"] == "image"
