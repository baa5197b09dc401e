"""peelcd: image-space collision detection between triangle meshes (docs/python.md).

    import numpy as np, peelcd
    world = peelcd.World()                     # backend "cpu", "osmesa" or "egl"
    a = world.add_rigid(peelcd.Mesh(V, F), pose=np.eye(4))
    r = world.collide()                        # options as in scene files: world.collide(stage="exact")
    if r:                                      # true when anything collides
        for p in r["pairs"]: print(p["a"], p["b"], p["colliding"])
"""
import os as _os

from ._peelcd import Detector as _Detector
from ._peelcd import Mesh, __version__, classes, exact_pairs, exact_self_pairs, gl_options, options
from ._peelcd import World as _World
from ._peelcd import load_mesh as _load_mesh
from ._peelcd import load_scene as _load_scene


class Result(dict):
    """A frame's result: a dict ({"pairs": [...], "is_collision": bool, "total_ms": float, ...})
    whose truth value is whether anything collides (a contact, or one object inside another)."""

    def __bool__(self):
        return bool(self.get("is_collision"))


class PairResult(dict):
    """One pair's result: a dict (triangles, kinds, segments, relation, is_collision, ...) whose
    truth value is whether the pair collides (a contact, or one object inside the other)."""

    def __bool__(self):
        return bool(self.get("is_collision"))


def _result(r):
    r["pairs"] = [PairResult(p) for p in r["pairs"]]
    return Result(r)


class World(_World):
    __doc__ = _World.__doc__

    def collide(_world, /, **options):  # noqa: N805 - `self` is an option's name (self=True)
        """One frame: every pair of bodies whose boxes overlap (a Result). Keyword options as in
        scene files (every key of options(), self included); max_contacts=1 asks for a first
        contact per pair."""
        return _result(_world._collide(options))


class Detector(_Detector):
    __doc__ = _Detector.__doc__

    def detect(_detector, /, *objects, **options):  # noqa: N805 - as World.collide
        """detect(objects, **options): one frame of the objects (Mesh, or dicts with mesh, name,
        self): a Result. Keyword options as in scene files, self included."""
        if len(objects) > 1:
            raise TypeError(f"detect() takes one list of objects, got {len(objects)} positional arguments")
        if objects:
            objects = objects[0]
        elif "objects" in options:
            objects = options.pop("objects")
        else:
            raise TypeError("detect() missing the list of objects")
        return _result(_detector._detect(list(objects), options))


def load_mesh(path):
    """Loads a mesh file (OBJ, PLY, STL, OFF, glTF, ...) as the command line does; path: str or os.PathLike."""
    return _load_mesh(_os.fspath(path))


def load_scene(path):
    """A scene file's objects in world space: a list of dicts with name, mesh and self."""
    return _load_scene(_os.fspath(path))


def collide(a, b, pose_a=None, pose_b=None, backend="cpu", **options):
    """One pair: two meshes, each at its pose (4x4, default identity). Returns the pair's
    PairResult (a dict: colliding, kinds, segments, relation, is_collision; true when the pair
    collides), always: when the two boxes do not overlap it is a false result with no triangles
    and relation "disjoint". Options are the scene files' keys (max_contacts=1: stop at the first
    contact; self=True adds each mesh's own self pairs to a World frame, not to this pair's
    result); on a GL backend also the GL options (gl_options()) and costs=FILE."""
    gl = {k: options.pop(k) for k in list(options) if k in gl_options() or k == "costs"}
    world = World(backend, **gl)
    world.add_rigid(a, pose_a)
    world.add_rigid(b, pose_b)
    for p in world.collide(**options)["pairs"]:
        if (p["a"], p["b"]) == (0, 1):
            return p
    return _separate_pair()


def _separate_pair():
    """The result of a pair whose boxes do not overlap: nothing collides, nothing was tested."""
    import numpy as np
    none = np.zeros((0, 2), np.uint32)
    return PairResult(a=0, b=1, name_a="", name_b="", colliding=none, triangles=none, kinds=[],
                      segments=np.zeros((0, 2, 3)), relation="disjoint",
                      relation_note="the two boxes do not overlap", is_collision=False, stage="none", path="none",
                      margin_fallback=False,
                      candidates=0, volume=None, distance=None, depth=None)


__all__ = ["Detector", "Mesh", "PairResult", "Result", "World", "classes", "collide", "exact_pairs", "exact_self_pairs", "gl_options",
           "load_mesh", "load_scene", "options", "__version__"]
