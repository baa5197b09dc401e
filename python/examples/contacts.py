"""Load two meshes, move one, print their contacts (docs/python.md)."""
import os
import sys

import numpy as np

import peelcd

fixtures = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "fixtures")
# The default scene's two meshes, in world space (a mesh file alone: peelcd.load_mesh(path)).
bunny, dragon = (o["mesh"] for o in peelcd.load_scene(os.path.join(fixtures, "scenes", "bunny_dragon.json")))

world = peelcd.World()                           # or peelcd.World("egl") on a GPU
a = world.add_rigid(bunny, name="bunny")
b = world.add_rigid(dragon, name="dragon")
for x in (0.0, 0.02, 0.04):
    pose = np.eye(4)
    pose[0, 3] = x                               # move the bunny along x
    world.set_pose(a, pose)
    for pair in world.collide()["pairs"]:
        tris = pair["colliding"]                 # (k, 2): bunny's triangle, dragon's triangle
        print("x=%.2f: %d contacts, relation %s, first %s" % (x, len(tris), pair["relation"], tris[:1].tolist()))
