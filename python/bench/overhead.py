"""The Python module's overhead (docs/python.md): a frame of the default scene from Python against
the same frame's time inside the library, side by side in one run (medians).

The World holds the two meshes as rigid bodies; each frame moves the bunny a little and collides.
"C++ frame" is the frame's own time as the library measures it (FrameResult timings.total);
"Python frame" is the wall time of set_pose + collide seen from Python (argument conversion,
the GIL released and taken again, the result's NumPy arrays built). Usage:
    PYTHONPATH=build/python /usr/bin/python3 python/bench/overhead.py [fixtures] [frames] [backend]
"""
import os
import statistics
import sys
import time

import numpy as np

import peelcd

fixtures = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "fixtures")
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 200
backend = sys.argv[3] if len(sys.argv) > 3 else "cpu"
objects = peelcd.load_scene(os.path.join(fixtures, "scenes", "bunny_dragon.json"))
print("peelcd %s, Python frame vs C++ frame: the default scene (%s), %d frames, backend %s, medians"
      % (peelcd.__version__, " vs ".join(o["name"] for o in objects), frames, backend))
for api in ("World", "Detector"):
    cpp, py = [], []
    if api == "World":
        world = peelcd.World(backend)
        a = world.add_rigid(objects[0]["mesh"])
        world.add_rigid(objects[1]["mesh"])
        pose = np.eye(4)
        def frame(f):
            pose[0, 3] = 0.001 * (f % 10)
            world.set_pose(a, pose)
            return world.collide()
    else:
        detector = peelcd.Detector(backend)
        def frame(f):
            return detector.detect(objects)
    for f in range(frames + 5):
        t0 = time.perf_counter()
        r = frame(f)
        t1 = time.perf_counter()
        if f >= 5:  # the first frames build what is kept
            py.append(1e3 * (t1 - t0))
            cpp.append(r["total_ms"])
    mp, mc = statistics.median(py), statistics.median(cpp)
    print("%-9s C++ frame %8.3f ms   Python frame %8.3f ms   ratio %.3f   contacts %d"
          % (api, mc, mp, mp / mc, sum(len(p["triangles"]) for p in r["pairs"])))
print("(Detector: the frame API takes the meshes whole each frame; its Python frame also copies them in.)")
