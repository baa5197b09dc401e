"""peelcd: image-space collision detection between triangle meshes (docs/python.md).

    import numpy as np, peelcd
    world = peelcd.World()                     # backend "cpu", "osmesa" or "egl"
    a = world.add_rigid(peelcd.Mesh(V, F), pose=np.eye(4))
    r = world.collide()                        # options as in scene files: world.collide(stage="exact")
    for p in r["pairs"]: print(p["a"], p["b"], p["triangles"])
"""
from ._peelcd import Detector, Mesh, World, __version__, classes, exact_pairs, gl_options, load_mesh, load_scene, options


def collide(a, b, pose_a=None, pose_b=None, backend="cpu", **options):
    """One pair: two meshes, each at its pose (4x4, default identity). Returns the pair's dict
    (triangles, kinds, segments, relation, is_collision), or None when their boxes do not overlap.
    Options are the scene files' keys; on a GL backend also the GL options (gl_options())."""
    gl = {k: options.pop(k) for k in list(options) if k in gl_options() or k == "costs"}
    world = World(backend, **gl)
    world.add_rigid(a, pose_a)
    world.add_rigid(b, pose_b)
    pairs = world.collide(**options)["pairs"]
    return pairs[0] if pairs else None


__all__ = ["Detector", "Mesh", "World", "classes", "collide", "exact_pairs", "gl_options", "load_mesh", "load_scene", "options", "__version__"]
