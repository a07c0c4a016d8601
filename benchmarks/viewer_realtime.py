"""Does the live viewer keep up with the wall clock? Serves the demo scene headless (no browser
attached) for 21 s and prints simulated seconds per wall second over the last 14 s and the
viewer's own real-time factor (steps per second × Δt) sampled each second (docs/viewer.md). Not
a test.

    python benchmarks/viewer_realtime.py              # the viewer's default threads
    python benchmarks/viewer_realtime.py --threads 2  # all engine threads
"""

from __future__ import annotations

import argparse
import threading
import time

from pliant.demo import DEMO_SCENE
from pliant.scene import load_scene
from pliant.view.viewer import LiveViewer


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--port", type=int, default=8093)
    args = ap.parse_args()
    v = LiveViewer(load_scene(DEMO_SCENE), port=args.port, threads=args.threads)
    samples: list[tuple[float, float, float]] = []

    def sample():
        time.sleep(5)  # past the start-up
        for _ in range(15):
            time.sleep(1)
            samples.append((v.sim.time, time.perf_counter(), v.realtime_factor))

    th = threading.Thread(target=sample)
    th.start()
    v.serve(duration=21)
    th.join()
    v.server.stop()
    (t0, w0, _), (t1, w1, _) = samples[0], samples[-1]
    print(f"{v.model.n_elements:,} tets, {v.model.threads} engine threads, dt = {v.sim.dt:.4g} s")
    print(f"simulated / wall over the last {w1 - w0:.0f} s: {(t1 - t0) / (w1 - w0):.3f}")
    print("real-time factor each second:", " ".join(f"{r:.2f}" for _, _, r in samples))


if __name__ == "__main__":
    main()
