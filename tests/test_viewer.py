"""The browser viewer in a real headless browser (Debian's chromium driven by Playwright).

The test set-up installs chromium with apt-get where it is missing (root); without a working
browser the test fails with the reason. Screenshots go to artifacts/ (PLIANT_ARTIFACTS)."""

import os
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import pliant as pl

from pliant.demo import DEMO_SCENE
from pliant.scene import load_scene

ARTIFACTS = Path(os.environ.get("PLIANT_ARTIFACTS", Path(__file__).parents[1] / "artifacts"))


@pytest.fixture(scope="module")
def chromium():
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None and os.geteuid() == 0 and shutil.which("apt-get"):
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        subprocess.run(["apt-get", "update", "-qq"], check=False, env=env, timeout=600, capture_output=True)
        subprocess.run(
            ["apt-get", "install", "-y", "-qq", "chromium"],
            check=False,
            env=env,
            timeout=900,
            capture_output=True,
        )
        exe = shutil.which("chromium")
    if exe is None:
        pytest.fail("no headless browser: install Debian's chromium (apt-get install chromium)")
    return exe


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _open(p, chromium, port):
    """A headless chromium page on the viewer (software WebGL)."""
    browser = p.chromium.launch(
        executable_path=chromium,
        headless=True,
        args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
    )
    page = browser.new_page(viewport={"width": 1000, "height": 700})
    page.goto(f"http://127.0.0.1:{port}")
    page.wait_for_selector("canvas", timeout=30000)
    return browser, page


def _shot_with_content(page, path: Path, timeout: float = 40.0) -> float:
    """Screenshots until the 3-D view shows something (software WebGL can take seconds to draw
    the first frame on a loaded 2-core machine); returns the non-background fraction."""
    deadline = time.time() + timeout
    while True:
        page.screenshot(path=str(path))
        frac = _non_background(path)
        if frac > 0.02 or time.time() > deadline:
            return frac
        time.sleep(1.0)


def _project(cam, p, W, H):
    """Screen pixel of world point p through viser's perspective camera (vertical fov, z up)."""
    pos, look = np.array(cam.position), np.array(cam.look_at)
    f = (look - pos) / np.linalg.norm(look - pos)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.asarray(p, float) - pos
    z, th = d @ f, np.tan(cam.fov / 2)
    return ((d @ r) / (z * th * W / H) + 1) / 2 * W, (1 - (d @ u) / (z * th)) / 2 * H


def _non_background(png: Path) -> float:
    """Fraction of the 3-D view's pixels (left part, away from the GUI panel) that are not the
    white background."""
    import matplotlib.image as mpimg

    img = mpimg.imread(png)[:, :600, :3]
    return float((img.min(axis=2) < 0.85).mean())


def test_viewer_in_a_real_browser(chromium):
    from playwright.sync_api import sync_playwright

    from pliant.view.viewer import LiveViewer

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    port = _free_port()
    v = LiveViewer(load_scene(DEMO_SCENE), host="127.0.0.1", port=port)
    assert v.server.get_host() == "127.0.0.1"  # loopback by default
    serve = threading.Thread(target=v.serve, kwargs=dict(duration=120), daemon=True)
    serve.start()
    try:
        with sync_playwright() as p:
            browser, page = _open(p, chromium, port)
            deadline = time.time() + 20
            while not v.server.get_clients() and time.time() < deadline:
                time.sleep(0.2)
            assert v.server.get_clients(), "the page did not connect to the viewer"
            # The body (and tool) are drawn: a fair share of the view is not background.
            assert _shot_with_content(page, ARTIFACTS / "viewer.png") > 0.02
            assert v.sim.time > 0 and v.steps_per_second > 0  # the simulation thread runs
            # Drag the tool's gizmo with the mouse: grab the tip of its blue (z) arrow, projected
            # through the initial camera, and pull it down to where that point would be 3 cm
            # lower (the axis drag follows the projected axis); then let the simulation run: the
            # tool comes down into the back and the displacement field under it changes.
            # Wait until the scene's own press is over (t > 0.85 s: the tool back at z = 0.13 m,
            # 1.9 cm above Spot's back at 0.096 m), so that the drag starts from a known pose.
            deadline = time.time() + 60
            while v.sim.time < 0.9 and time.time() < deadline:
                time.sleep(0.2)
            assert v.sim.time >= 0.9, f"the simulation reached only t = {v.sim.time:.3f} s in 60 s"
            X = v.model.reference_positions
            under = np.linalg.norm(X - [0.0, -0.055, 0.1], axis=1) < 0.02
            v.playing = False
            time.sleep(0.3)
            with v.lock:  # the simulation thread has finished its last chunk
                before = v.sim.displacements[under].copy()
                _, pos = v.model.tools[1].pose(v.sim.time)
            scale = 0.5 * float(np.ptp(X, axis=0).max())  # the gizmo's size (LiveViewer)
            grip = pos + [0.0, 0.0, 0.9 * scale]
            sx, sy = _project(v.server.initial_camera, grip, 1000, 700)
            tx, ty = _project(v.server.initial_camera, grip - [0.0, 0.0, 0.03], 1000, 700)
            drag = v._drags[1]
            dragged_at = drag.last
            page.mouse.move(sx, sy)
            page.mouse.down()
            page.mouse.move(tx, ty, steps=8)
            page.mouse.up()
            # The drag's messages reach the server one by one (about one a second with software
            # WebGL on 2 cores): wait for its end, so that the tool's target is where the mouse
            # let go, not part of the way.
            deadline = time.time() + 60
            while time.time() < deadline and (drag.last == dragged_at or drag.dragging):
                time.sleep(0.1)
            assert drag.last > dragged_at, "the mouse drag did not reach the tool's gizmo"
            assert not drag.dragging, "the drag did not end within 60 s"
            target = v.sim.solver.tools[1].keys[-1][1:4]  # the solver owns the trajectories
            # Dragged down by 3 cm, to within 6 mm (a few pixels of the projected axis): its
            # lowest point at least 8 mm into the back.
            assert pos[2] - 0.036 < target[2] < pos[2] - 0.024, (pos, target)
            assert np.hypot(*(target - pos)[:2]) < 0.006, (pos, target)  # along the axis only
            with v.lock:
                v.sim.run(until=v.sim.time + 0.3)
                after = v.sim.displacements[under]
            assert np.abs(after - before).max() > 1e-3
            assert np.linalg.norm(v.sim.tool_force(1)[0]) > 0
            v.playing = True
            time.sleep(2)
            page.screenshot(path=str(ARTIFACTS / "viewer_pressed.png"))
            browser.close()
    finally:
        v.stop_event.set()
        serve.join(timeout=5)
        v.server.stop()


def test_a_paused_drag_stays_where_it_was_left():
    """The gizmo follows its tool's keyframes, but not back to where a paused tool still is: a
    drag whose messages came more than a second apart (software WebGL in CI) had its gizmo, and
    with the drag's last message its target, snapped back to the grip. The drag's messages are
    given here as viser hands them over (its phases, in order), without a browser."""
    import asyncio
    from types import SimpleNamespace

    from pliant.view.viewer import LiveViewer

    v = LiveViewer(load_scene(DEMO_SCENE), port=_free_port())
    try:
        v.playing = False
        v.draw()
        ctrl = v.controls[1]
        p0, q0 = np.array(ctrl.position), np.array(ctrl.wxyz)
        _, pos = v.sim.solver.tools[1].pose(v.sim.time)
        assert np.allclose(p0, pos)  # the gizmo starts on its tool
        callback = v._on_drag(v.move_tool, 1, v._drags[1])

        def message(phase, position):
            ctrl.position = tuple(position)  # what viser does with the browser's pose
            asyncio.run(callback(SimpleNamespace(phase=phase, target=ctrl)))

        message("start", p0)
        message("update", p0 - [0.0, 0.0, 0.01])
        for _ in range(12):  # 1.2 s of drawing with the mouse held still
            v.draw()
            time.sleep(0.1)
        message("update", p0 - [0.0, 0.0, 0.02])
        message("end", p0 - [0.0, 0.0, 0.02])
        for _ in range(12):  # and 1.2 s after it let go, still paused
            v.draw()
            time.sleep(0.1)
        assert np.allclose(ctrl.position, p0 - [0.0, 0.0, 0.02]), ctrl.position
        assert np.allclose(v.sim.solver.tools[1].keys[-1][1:4], p0 - [0.0, 0.0, 0.02])
        with v.lock:  # played on, the tool reaches the target and the gizmo stays on it
            v.sim.run(until=v.sim.time + 0.05)
        v.draw()
        _, pos = v.sim.solver.tools[1].pose(v.sim.time)
        assert np.allclose(pos, p0 - [0.0, 0.0, 0.02]) and np.allclose(ctrl.position, pos)
        v.reset()  # the gizmo goes back with its tool
        v.draw()
        assert np.allclose(ctrl.position, p0) and np.allclose(ctrl.wxyz, q0)
    finally:
        v.server.stop()


def test_addresses_the_viewer_cannot_listen_on_are_refused():
    """viser tries an address on a thousand ports, then waits for ever: an unknown host or another
    machine's address hung `pliant view`. A port another program holds gives the next free one,
    which the viewer reports (it printed the port asked for)."""
    import socket
    import subprocess
    import sys

    from pliant.view.viewer import LiveViewer, serve_on

    cantilever = Path(__file__).parents[1] / "examples" / "cantilever.toml"
    pliant = Path(sys.executable).with_name("pliant")
    for host, says in [
        ("192.0.2.1", "cannot listen on 192.0.2.1"),
        ("no-such-host.invalid", "not an address"),
    ]:
        r = subprocess.run(
            [str(pliant), "view", str(cantilever), "--host", host], capture_output=True, text=True, timeout=60
        )
        assert r.returncode == 2 and says in r.stderr and "Traceback" not in r.stderr, r.stderr
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        server = serve_on("127.0.0.1", port)
        try:
            assert server.get_port() not in (port, 0)
        finally:
            server.stop()
    with pytest.raises(pl.InputError, match="threads = 0"):  # was taken as "automatic"
        LiveViewer(load_scene(cantilever), port=_free_port(), threads=0)


def test_playback_of_a_results_folder(chromium, tmp_path):
    from playwright.sync_api import sync_playwright

    from pliant.runner import run_scene
    from pliant.view.viewer import PlaybackViewer

    sc = load_scene(DEMO_SCENE)
    sc.duration, sc.frames, sc.png = 0.05, 4, False
    run_scene(sc, tmp_path, progress=False)
    port = _free_port()
    v = PlaybackViewer(tmp_path, port=port)
    assert len(v.files) == 5
    v.show(4)
    with sync_playwright() as p:
        browser, page = _open(p, chromium, port)
        frac = _shot_with_content(page, ARTIFACTS / "playback.png")
        browser.close()
    assert frac > 0.02
    v.server.stop()


def test_playback_names_a_frame_it_cannot_read(tmp_path):
    """A frame damaged after the folder was opened: the slider's callback (the server's thread)
    raised; the label now names the file and the last good frame stays."""
    from pliant.runner import run_scene
    from pliant.view.viewer import PlaybackViewer

    sc = load_scene(DEMO_SCENE)
    sc.duration, sc.frames, sc.png = 0.05, 4, False
    run_scene(sc, tmp_path, progress=False)
    v = PlaybackViewer(tmp_path, port=_free_port())
    try:
        (tmp_path / "frame_00003.vtu").write_text("garbage")
        assert v.shown(2) and "frame 3/5" in v.label.content
        assert not v.shown(3)
        assert "frame 4/5 cannot be shown" in v.label.content and "frame_00003.vtu" in v.label.content
    finally:
        v.server.stop()


EXAMPLES = Path(__file__).parents[1] / "examples"

GRASP_SCENE = """
[mesh]
primitive = "box"
size = [0.02, 0.02, 0.02]
cells = [4, 4, 4]
translate = [0.0, 0.0, 0.01]
[[material]]
type = "neo-hookean"
E = 2e4
nu = 0.4
density = 1000.0
[solver]
duration = 1.0
damping = 20.0
[[load]]
type = "gravity"
[[tool]]
type = "plane"
[[tool]]
type = "box"
name = "jaws"
half_extents = [0.006, 0.006, 0.003]
position = [0.0, 0.0, 0.023]
"""


def test_the_live_viewer_cuts_with_a_dragged_blade_and_resets():
    """The viewer runs a scene with a blade (its keyframes cut the cantilever through), draws the
    new topology, moves the blade where its gizmo is dragged (cutting on the way), and Reset
    brings back the uncut model."""
    from pliant.view.viewer import LiveViewer

    v = LiveViewer(load_scene(EXAMPLES / "cut_cantilever.toml"), port=_free_port())
    try:
        n0 = v.model.n_nodes
        with v.lock:
            v.sim.run(until=0.3)
        v.draw()
        assert v.sim.model.n_nodes > n0 and v._surface[0] is v.sim.model
        assert "cuts" in v.status.content
        v.reset()
        assert v.sim.model is v.model and v.sim.time == 0.0
        # Drag the scalpel from its start straight down through the beam at x = 7 cm.
        start = np.array([0.0725, 0.0, 0.02])
        v.move_blade(0, start, v.scene.blades[0].keys[0][4:])
        with v.lock:
            v.sim.run(until=v.scene.blades[0].keys[-1][0])
        v.move_blade(0, start - [0.0, 0.0, 0.06], v.scene.blades[0].keys[0][4:])
        with v.lock:
            v.sim.run(until=v.scene.blades[0].keys[-1][0] + 0.01)
        assert v.sim.cutter.events and v.sim.model.n_nodes > n0
        v.draw()
    finally:
        v.stop_event.set()
        v.server.stop()


def test_the_live_viewer_colours_a_scene_by_body(tmp_path):
    """With soft contact the viewer offers to colour the surface by body: each body one colour,
    the base (body 0) the lowest and the block on it (body 1) the highest of the colour bar."""
    from pliant.view.viewer import BODY_FIELD, LiveViewer

    from test_scene_bodies import SCENE

    path = tmp_path / "two.toml"
    path.write_text(SCENE)
    v = LiveViewer(load_scene(path), port=_free_port())
    try:
        assert BODY_FIELD in v.field_dropdown.options
        v.field = BODY_FIELD
        v.draw()
        assert v.colourbar.content.startswith(f"{BODY_FIELD}: 0 ") and "… 1 " in v.colourbar.content
    finally:
        v.stop_event.set()
        v.server.stop()


def test_the_live_viewer_grasps_and_releases(tmp_path):
    from pliant.view.viewer import LiveViewer

    f = tmp_path / "grasp.toml"
    f.write_text(GRASP_SCENE)
    v = LiveViewer(load_scene(f), port=_free_port())
    try:
        assert list(v.grasp_buttons) == [1]  # the plane does not grasp
        v.toggle_grasp(1)
        assert v.grasp_buttons[1].label.startswith("Release")
        with v.lock:
            v.sim.run(steps=5)
        assert set(v.sim.state.held.values()) == {1}
        v.draw()
        assert "held" in v.status.content
        v.toggle_grasp(1)
        with v.lock:
            v.sim.run(steps=1)
        assert v.sim.state.held == {}
    finally:
        v.stop_event.set()
        v.server.stop()


def _drawn(viewer):
    """The meshes the viewer sends to the browser (add_mesh_trimesh's), in order."""
    sent = []
    add = viewer.server.scene.add_mesh_trimesh
    viewer.server.scene.add_mesh_trimesh = lambda name, mesh, **kw: (
        sent.append(mesh),
        add(name, mesh, **kw),
    )[1]
    return sent


def _two_sided(mesh, n_triangles: int, n_nodes: int):
    """A sheet drawn from both sides: each triangle twice, the second turned over on a copy of the
    vertices at the same places."""
    F, V = np.asarray(mesh.faces), np.asarray(mesh.vertices)
    assert F.shape == (2 * n_triangles, 3) and V.shape == (2 * n_nodes, 3)
    np.testing.assert_array_equal(F[n_triangles:], F[:n_triangles, ::-1] + n_nodes)
    np.testing.assert_array_equal(V[n_nodes:], V[:n_nodes])


def _range_within(text: str, tension: np.ndarray) -> bool:
    """Whether the first range shown in ``text`` ("field: lo (dark blue) … hi (yellow)" or
    "...; field lo … hi") lies within the membranes' own tensions, to the 3 digits shown, and its
    top is a pull (> 0): node averages of the membranes' values."""
    import re

    lo, hi = (float(x) for x in re.search(r"(\S+) (?:\(dark blue\) )?… (\S+)", text).groups())
    slack = 5e-3 * np.abs(tension).max()
    return tension.min() - slack <= lo <= hi <= tension.max() + slack and hi > 0


def test_the_viewer_draws_membranes_alone(tmp_path):
    """NiftySim's membrane_stretch_nonlinear_irregular.xml (tests/data: 198 Neo-Hookean membrane
    triangles, no tets, one edge pulled 1 cm along the sheet; its displacements against NiftySim's
    run: tests/test_niftysim_membranes.py): the live viewer draws the sheet itself, from both
    sides, coloured by the membranes' larger principal tension averaged at the nodes, so the range
    shown lies within the membranes' own (to the 3 digits shown) and its top is a pull (> 0). Its
    results folder plays back the same way, from the frames' membrane_max_tension."""
    import meshio
    from typer.testing import CliRunner

    from pliant.cli import app
    from pliant.io.niftysim import load_niftysim
    from pliant.view.viewer import TENSION_FIELD, LiveViewer, PlaybackViewer

    model = Path(__file__).parent / "data" / "niftysim_membrane_stretch_nonlinear_irregular.xml"
    scene = load_niftysim(model)
    v = LiveViewer(scene, port=_free_port())
    n_nodes = np.unique(v.model.membrane_faces).size
    try:
        sent = _drawn(v)
        assert v.field_dropdown.options[0] == TENSION_FIELD == v.field
        v.sim.run(until=scene.duration)  # the edge pulled
        v.draw()
        _two_sided(sent[-1], 198, n_nodes)
        tension = v.model.membrane_results(v.sim.state)["max_tension"]
        assert v.colourbar.content.startswith(TENSION_FIELD) and _range_within(v.colourbar.content, tension)
    finally:
        v.stop_event.set()
        v.server.stop()
    out = tmp_path / "out"
    assert CliRunner().invoke(app, ["run", str(model), "-o", str(out)]).exit_code == 0
    p = PlaybackViewer(out, port=_free_port())
    try:
        sent = _drawn(p)
        p.show(len(p.files) - 1)
        _two_sided(sent[-1], 198, n_nodes)
        tension = meshio.read(p.files[-1]).cell_data["membrane_max_tension"][0]
        assert "tension [N/m]" in p.label.content and _range_within(p.label.content, tension)
    finally:
        p.server.stop()


def _cube_and_sheet():
    """A 2 cm cube of 2 × 2 × 2 cells fixed at its base, and beside it (3 cm above, a node of it
    off the cube) a 4 cm sheet of 32 Neo-Hookean membrane triangles pinned at its corners, both
    under gravity: the scene a NiftySim model such as two_cubes_sheet.xml becomes without contact."""
    from pliant.job import Scene
    from pliant.mesh import grid_tets

    X, T = grid_tets(np.linspace(0, 0.02, 3), np.linspace(0, 0.02, 3), np.linspace(0, 0.02, 3))
    n, g = 5, np.linspace(0, 0.04, 5)
    S = np.array([[x, y, 0.05] for y in g for x in g])
    F = [[a, a + 1, a + n + 1] for a in range(n * n - n) if a % n < n - 1]
    F += [[a, a + n + 1, a + n] for a in range(n * n - n) if a % n < n - 1]
    b = pl.ModelBuilder()
    b.add_mesh(np.vstack([X, S]), T)
    b.set_material(pl.NeoHookean(E=1e4, nu=0.3), density=1000.0)
    b.add_membrane(np.array(F) + len(X), pl.NeoHookeanMembrane(mu=1e3, thickness=1e-3, density=1000.0))
    corners = len(X) + np.array([0, n - 1, n * (n - 1), n * n - 1])
    b.fix(np.concatenate([corners, np.nonzero(X[:, 2] == 0)[0]]))
    b.add_gravity((0, 0, -9.81), np.arange(len(X) + len(S)))
    return Scene("cube and sheet", b, duration=0.05, frames=2)


def test_the_viewer_draws_a_sheet_beside_a_solid(tmp_path):
    """Membranes with a node off the tets (a sheet beside a solid) are drawn too, from both
    sides, coloured by their tension (sagging under gravity between pinned corners: a pull),
    beside the solid's boundary (6 faces × 4 squares × 2 = 48 triangles), live and played back;
    before, only the solid was drawn."""
    import meshio

    from pliant.runner import run_scene
    from pliant.view.viewer import LiveViewer, PlaybackViewer

    scene = _cube_and_sheet()
    v = LiveViewer(scene, port=_free_port())
    try:
        sent = _drawn(v)
        v.sim.run(until=scene.duration)
        v.draw()
        body, sheet = sent[-2:]
        assert len(body.faces) == 48
        _two_sided(sheet, 32, 25)
        tension = v.model.membrane_results(v.sim.state)["max_tension"]
        assert _range_within(v.colourbar.content.split("sheets beside it")[1], tension)
    finally:
        v.stop_event.set()
        v.server.stop()
    run_scene(scene, tmp_path, progress=False)
    p = PlaybackViewer(tmp_path, port=_free_port())
    try:
        sent = _drawn(p)
        p.show(len(p.files) - 1)
        _two_sided(sent[-1], 32, 25)
        frame = meshio.read(p.files[-1])
        tension = frame.cell_data_dict["membrane_max_tension"]["triangle"]
        assert _range_within(p.label.content.split("sheets beside it")[1], tension)
    finally:
        p.server.stop()
