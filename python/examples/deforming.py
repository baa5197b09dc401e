"""A deforming loop: a cloth folding through itself over a ball, self-collision on (docs/python.md)."""
import numpy as np

import peelcd

n = 20  # a sheet of n x 3n quads, folded over itself along x = 1
u, v = np.meshgrid(np.linspace(0, 1, 3 * n + 1), np.linspace(0, 1, n + 1))
ids = np.arange(u.size).reshape(u.shape)
quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], axis=-1).reshape(-1, 4)
F = np.ascontiguousarray(np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]), dtype=np.int32)

def cloth(t):
    """The fold at time t: the top layer (u > 2/3) sags through the bottom (u < 1/3) as t grows."""
    x = np.where(u <= 1 / 3, 3 * u, np.where(u < 2 / 3, 1.0, 1.0 - (3 * u - 2)))
    sag = 0.4 * t * np.exp(-((x - 0.5) ** 2 + (v - 0.5) ** 2) / 0.04)
    z = np.where(u <= 1 / 3, 0.0, np.where(u < 2 / 3, 0.3 * (1.2 - t) * (3 * u - 1), 0.3 * (1.2 - t) - sag))
    return np.ascontiguousarray(np.stack([x, v, z], axis=-1).reshape(-1, 3))

world = peelcd.World()
body = world.add_deforming(peelcd.Mesh(cloth(0.0), F), name="cloth", self_collision=True)
for f in range(6):
    world.set_vertices(body, cloth(f / 5))       # new vertices every frame: the tree is refitted
    pairs = world.collide()["pairs"]
    self_pairs = sum(len(p["colliding"]) for p in pairs if p["a"] == p["b"])
    print("frame %d: %d self pairs" % (f, self_pairs))
