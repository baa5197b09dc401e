"""peelcd: image-space collision detection between triangle meshes (docs/python.md).

    import numpy as np, peelcd
    world = peelcd.World()                     # backend "cpu", "osmesa" or "egl"
    a = world.add_rigid(peelcd.Mesh(V, F), pose=np.eye(4))
    r = world.collide()                        # options as in scene files: world.collide(stage="exact")
    for p in r["pairs"]: print(p["a"], p["b"], p["triangles"])
"""
from ._peelcd import Detector, Mesh, World, __version__, classes, exact_pairs, load_mesh, load_scene, options


def collide(a, b, pose_a=None, pose_b=None, backend="cpu", **options):
    """One pair: two meshes, each at its pose (4x4, default identity). Returns the pair's dict
    (triangles, kinds, segments, relation, is_collision), or None when their boxes do not overlap."""
    world = World(backend)
    world.add_rigid(a, pose_a)
    world.add_rigid(b, pose_b)
    pairs = world.collide(**options)["pairs"]
    return pairs[0] if pairs else None


__all__ = ["Detector", "Mesh", "World", "classes", "collide", "exact_pairs", "load_mesh", "load_scene", "options", "__version__"]
