"""Interactive viewer in the browser (viser): the deforming body coloured by von Mises stress,
displacement or (with soft contact) body, rigid tools draggable with a transform gizmo while the
simulation runs in real time, play / pause / reset / step, live stiffness and damping, the tool's
contact force as a number and an arrow; and playback of a results folder with a time slider.

Threads: the simulation runs in its own thread (sub-stepping at its stable Δt to follow the wall
clock); the drawing loop sends the surface to the browser at about 20 frames per second.
"""

from __future__ import annotations

import asyncio
import threading
import time
from pathlib import Path

import numpy as np

from .. import _core
from ..contact import quat_from_matrix
from ..errors import InputError, PliantError
from ..io.files import MISSING, file_problem, read_meshio
from ..io.results import INDEX
from ..mesh.topology import boundary_faces, faces_off

BODY_FIELD = "body"  # the colour choice that tells a scene's bodies apart (Model.bodies)
STRESS_FIELD = "von Mises stress [Pa]"  # the tets' (Model.element_results)
TENSION_FIELD = "membrane tension [N/m]"  # membranes alone: the larger principal (Model.membrane_results)
DISPLACEMENT_FIELD = "displacement [m]"


def _colours(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    import matplotlib

    norm = (np.asarray(values) - lo) / (hi - lo if hi > lo else 1.0)
    return (matplotlib.colormaps["viridis"](np.clip(norm, 0, 1))[:, :3] * 255).astype(np.uint8)


def _frame_camera(server, X: np.ndarray):
    """Initial camera looking at the body from a 3/4 view, z up."""
    lo, hi = X.min(axis=0), X.max(axis=0)
    c, r = (lo + hi) / 2, float(np.linalg.norm(hi - lo))
    server.initial_camera.up = (0.0, 0.0, 1.0)
    server.initial_camera.look_at = tuple(c)
    server.initial_camera.position = tuple(c + r * np.array([1.2, -1.2, 0.8]))


def serve_on(host: str, port: int):
    """A viser server on ``host``; on ``port``, or the next free port when another program has it
    (``server.get_port()`` says which). An address this machine cannot listen on is refused first:
    viser would try it on a thousand ports, then wait for ever."""
    import viser

    check_address(host, port)
    return viser.ViserServer(host=host, port=port, verbose=False)


def check_address(host: str, port: int) -> None:
    """InputError unless this machine can listen on ``host``: an unknown name, another machine's
    address, a port it may not open (below 1024 without privileges). A port in use passes."""
    import errno
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as e:
        raise InputError(f"--host {host!r}: not an address of this machine ({e})") from None
    reason = "no address"
    for family, kind, proto, _, address in infos:
        with socket.socket(family, kind, proto) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind(address)
                return
            except OSError as e:
                if e.errno == errno.EADDRINUSE:
                    return  # viser takes the next free port
                reason = e.strerror or str(e)
    raise InputError(f"cannot listen on {host}:{port}: {reason}")


def _coloured_mesh(V: np.ndarray, F: np.ndarray, values: np.ndarray, two_sided: bool = False):
    """A trimesh of vertices V (n, 3) [m] and triangles F (k, 3) coloured by ``values`` (n,)
    (viridis over their range), and that range (lo, hi). ``two_sided`` (a sheet of membranes): each
    triangle comes twice, the second turned over on its own copy of the vertices, so that both
    sides are lit and seen."""
    import trimesh

    lo, hi = float(values.min()), float(values.max())
    colours = _colours(values, lo, hi)
    if two_sided:
        V, colours, F = np.vstack([V, V]), np.vstack([colours, colours]), np.vstack([F, F[:, ::-1] + len(V)])
    return trimesh.Trimesh(V, F, process=False, vertex_colors=colours), (lo, hi)


class _Surface:
    """What the viewer draws as a compact triangle mesh, with node → vertex mapping: the boundary
    of a tet mesh, or, for membranes alone, the membrane triangles themselves (``sheet``: drawn
    from both sides)."""

    def __init__(self, faces: np.ndarray, owner: np.ndarray, sheet: bool = False):
        self.nodes = np.unique(faces)
        remap = np.full(int(faces.max()) + 1, -1)
        remap[self.nodes] = np.arange(self.nodes.size)
        self.faces = remap[faces]
        self.owner = owner  # element (tet or membrane) behind each face
        self.sheet = sheet

    @classmethod
    def of_tets(cls, tets: np.ndarray) -> "_Surface":
        return cls(*boundary_faces(tets))

    @classmethod
    def of_sheet(cls, triangles: np.ndarray) -> "_Surface":
        """Membrane triangles (K, 3) (node ids), each its own face."""
        return cls(np.asarray(triangles), np.arange(len(triangles)), sheet=True)

    @classmethod
    def of_model(cls, model) -> "_Surface":
        """A model's tets' boundary (membranes on it lie on those faces), or its membranes alone."""
        return cls.of_tets(model.tets) if model.n_elements else cls.of_sheet(model.membrane_faces)

    @classmethod
    def sheets_beside(cls, triangles: np.ndarray, tets: np.ndarray) -> "_Surface | None":
        """The membrane triangles (K, 3) with a node off the tets (M, 4), a sheet beside a solid
        (NiftySim's two_cubes_sheet.xml), owned by their index
        among ``triangles``; None where there are none or no tets (membranes alone: of_sheet)."""
        if not len(tets) or not len(triangles):
            return None
        free = faces_off(triangles, tets)
        return cls(np.asarray(triangles)[free], free, sheet=True) if free.size else None

    def node_values(self, element_values: np.ndarray) -> np.ndarray:
        """Average of the adjacent faces' element values at each surface vertex."""
        acc = np.zeros(self.nodes.size)
        cnt = np.zeros(self.nodes.size)
        for k in range(3):
            np.add.at(acc, self.faces[:, k], element_values[self.owner])
            np.add.at(cnt, self.faces[:, k], 1)
        return acc / np.maximum(cnt, 1)


class _Drag:
    """One gizmo's drag as the browser reports it, and whether the gizmo should follow its
    object's pose (keyframes, a reset). viser awaits async callbacks in message order, so the
    phases arrive as the browser sent them."""

    def __init__(self):
        self.dragging = False
        self.last = 0.0  # perf_counter of the last drag message
        self.seen = None  # the object's pose (position and wxyz) the gizmo last followed

    def heard(self, phase: str):
        self.dragging = phase != "end"
        self.last = time.perf_counter()

    def follows(self, position, wxyz) -> bool:
        """Whether to move the gizmo to the object's pose (position [m], wxyz): not while a drag
        is on, nor for a second after one (the object is on its way to where the drag left it),
        and only when the pose has changed since the gizmo last followed it (paused, a tool
        stays where it was while its target is where the drag left the gizmo)."""
        pose = np.concatenate([np.asarray(position, float), np.asarray(wxyz, float)])
        if self.dragging or time.perf_counter() - self.last < 1.0:
            return False
        if self.seen is not None and np.allclose(pose, self.seen):
            return False
        self.seen = pose
        return True


class LiveViewer:
    """Serve a scene live. ``host`` 127.0.0.1 by default; ``--host 0.0.0.0`` exposes it."""

    def __init__(self, scene, host: str = "127.0.0.1", port: int = 8080, threads: int | None = None):
        from ..tled import Simulation
        from ..tled.model import _auto_threads

        self.scene = scene
        # The engine leaves one core to the drawing loop: on 2 cores the demo then keeps up with the
        # wall clock (1 engine thread: simulated/wall 1.00, capacity 1.0-2.4x; 2 threads: 0.99, with
        # the capacity dipping to 0.7x while a frame is drawn; docs/viewer.md).
        auto = max(1, min(_auto_threads(scene.builder.n_elements), _core.max_threads() - 1))
        threads = threads if threads is not None else scene.threads or auto  # 0 is refused, not automatic
        self.model = scene.builder.finalize(scene.dtype, threads=threads)  # at reset
        # An interactive session may run for hours: keep the last 100,000 steps of tool forces.
        from ..runner import scene_step

        dt = scene_step(scene, self.model)  # a NiftySim H8 model's step divided as `pliant run` does
        self.sim = Simulation(self.model, dt=dt, safety=scene.safety, history_steps=100_000)
        for blade in scene.blades:  # blades cut as the simulation runs (sim.model then changes)
            self.sim.add_blade(blade)
        self._solver0 = self.sim.solver
        self.dt0 = self.sim.solver.dt
        self._dt_model = self.model  # the model dt0 belongs to (a cut may lower the step)
        self._surface = self._surfaces(self.model)
        self.embedding = None  # the fine surface of the scene, when it has one
        if scene.meta.get("embed_surface"):
            from ..mesh import embed_surface

            Ve, Fe = scene.meta["embed_surface"]
            self.embedding = embed_surface(self.model.reference_positions, self.model.tets, Ve, Fe)
        if self.sim.cutter is not None:
            self.sim.cutter.embedding = self.embedding  # it opens along the cuts
        self.lock = threading.Lock()
        self.playing = True
        self.stop_event = threading.Event()
        self.steps_per_second = 0.0
        self.realtime_factor = 0.0
        # Membranes alone (a NiftySim shell model): coloured by their tension, not by tets' stress.
        self.fields = [TENSION_FIELD if self.model.n_elements == 0 else STRESS_FIELD, DISPLACEMENT_FIELD]
        if self.model.bodies is not None:  # soft contact: several bodies, told apart by colour
            self.fields.append(BODY_FIELD)
        self.field = self.fields[0]
        self.error = ""
        self.server = serve_on(host, port)
        _frame_camera(self.server, self.model.reference_positions)
        self._build_gui()
        self._build_scene()

    # --- GUI ------------------------------------------------------------------------------
    def _build_gui(self):
        g = self.server.gui
        m = self.model
        size = f"{m.n_elements:,} tets" if m.n_elements else f"{m.n_membranes:,} membranes"
        g.add_markdown(f"**pliant** — {self.scene.title}: {size}, Δt = {self.sim.solver.dt:.3g} s")
        self.play_button = g.add_button("Pause")
        self.step_button = g.add_button("Single step")
        self.reset_button = g.add_button("Reset")
        self.field_dropdown = g.add_dropdown("Colour by", self.fields)
        self.stiffness = g.add_slider("Stiffness × (live)", 0.25, 4.0, 0.05, 1.0)
        self.damping = g.add_slider("Damping α [1/s] (live)", 0.0, 100.0, 0.5, float(self.sim.solver.damping))
        self.grasp_buttons = {}
        for k, tool in enumerate(self.model.tools):
            if tool.kind != _core.ToolKind.Plane:
                button = g.add_button(f"Grasp with {tool.name}")
                button.on_click(lambda _, k=k: self.toggle_grasp(k))
                self.grasp_buttons[k] = button
        self.status = g.add_markdown("")
        self.colourbar = g.add_markdown("")
        self.force_text = g.add_markdown("")

        @self.play_button.on_click
        def _(_):
            self.playing = not self.playing
            self.play_button.label = "Pause" if self.playing else "Play"

        @self.step_button.on_click
        def _(_):
            with self.lock:
                self.sim.step()

        @self.reset_button.on_click
        def _(_):
            self.reset()

        @self.field_dropdown.on_update
        def _(_):
            self.field = self.field_dropdown.value

        @self.stiffness.on_update
        def _(_):
            with self.lock:
                self.sim.solver.scale_materials(float(self.stiffness.value))
                # Stiffer material, faster waves: the stable step shrinks as 1/sqrt(factor).
                self.sim.solver.dt = self.dt0 / np.sqrt(max(1.0, float(self.stiffness.value)))

    def reset(self):
        """Back to the scene's model and state at t = 0: cuts undone, tools, blades and grasps as
        the scene has them."""
        with self.lock:
            self.sim.model, self.sim.solver = self.model, self._solver0
            self.sim.state = self.model.state()
            self.dt0, self._dt_model = self._solver0.dt, self.model
            self.error = ""
            for k, t in enumerate(self.sim.solver.tools):
                t.keys = [k0.copy() for k0 in self._initial_keys[k]]
                t.grips = list(self._initial_grips[k])
            self.sim.solver.set_tool_keys() if self.model.tools else None
            for j, b in enumerate(self.scene.blades):
                b.keys = [k0.copy() for k0 in self._initial_blade_keys[j]]
            if self.sim.cutter is not None:
                self.sim.cutter.embedding, self.sim.cutter.events = self.embedding, []
        for d in self._drags + self._blade_drags:  # the gizmos go back with their objects
            d.seen = None

    def toggle_grasp(self, k: int):
        """What tool k's grasp button does: close it (it holds the surface nodes within its reach,
        or half the smallest element altitude if it has none) or open it, from the next step."""
        with self.lock:
            tool = self.sim.solver.tools[k]
            try:
                if len(tool.grips) % 2:
                    self.sim.release(k)
                else:
                    self.sim.grasp(k, reach=tool.reach or 0.5 * self.model.min_altitude)
            except InputError as e:  # a grasp the scene has scheduled later
                self.error = str(e)
                return
            self.grasp_buttons[k].label = f"{'Release' if len(tool.grips) % 2 else 'Grasp with'} {tool.name}"

        @self.damping.on_update
        def _(_):
            with self.lock:
                self.sim.solver.damping = float(self.damping.value)

    def _build_scene(self):
        sc = self.server.scene
        self._initial_keys = [[k.copy() for k in t.keys] for t in self.sim.solver.tools]
        self._initial_grips = [list(t.grips) for t in self.sim.solver.tools]
        self._initial_blade_keys = [[k.copy() for k in b.keys] for b in self.scene.blades]
        self.controls = []
        self._drags = [_Drag() for _ in self.model.tools]
        self._blade_drags = [_Drag() for _ in self.scene.blades]
        ext = float(np.ptp(self.model.reference_positions, axis=0).max())
        for k, tool in enumerate(self.model.tools):
            R, p = tool.pose(0.0)
            from ..contact import Box, Capsule, Plane, Sphere

            q = quat_from_matrix(R)
            name = f"/tools/{k}"
            if isinstance(tool, Plane):
                sc.add_grid(name, width=2 * ext, height=2 * ext, position=p, wxyz=q)
                self.controls.append(None)
                continue
            ctrl = sc.add_transform_controls(name, scale=0.5 * ext, position=p, wxyz=q)
            if isinstance(tool, Sphere):
                sc.add_icosphere(f"{name}/shape", radius=tool.radius, color=(200, 80, 80))
            elif isinstance(tool, Capsule):
                sc.add_cylinder(f"{name}/shape", radius=tool.radius, height=tool.length, color=(200, 80, 80))
            elif isinstance(tool, Box):
                sc.add_box(f"{name}/shape", dimensions=tuple(2 * tool.half), color=(200, 80, 80))
            ctrl.on_update(self._on_drag(self.move_tool, k, self._drags[k]))
            self.controls.append(ctrl)
        self.blade_controls = []
        for j, blade in enumerate(self.scene.blades):  # a thin plate: the edge at its local z = 0
            R, p = blade.pose(0.0)
            ctrl = sc.add_transform_controls(
                f"/blades/{j}", scale=0.5 * ext, position=p, wxyz=quat_from_matrix(R)
            )
            depth = max(blade.depth, 0.02 * blade.length)
            sc.add_box(
                f"/blades/{j}/shape",
                dimensions=(blade.length, 0.005 * blade.length, depth),
                position=(0.0, 0.0, depth / 2),
                color=(150, 150, 170),
            )
            ctrl.on_update(self._on_drag(self.move_blade, j, self._blade_drags[j]))
            self.blade_controls.append(ctrl)

    def _on_drag(self, move, k: int, drag: _Drag):
        """The gizmo callback: an async one, so that viser runs it in message order; it notes the
        drag's phase and moves the object (``move(k, position, wxyz)``) on each update, taking
        the pose the message brought (a pose read later may be the drawing loop's)."""

        async def on_update(event):
            phase = event.phase  # "start", "update" or "end" (viser >= 1.1)
            position, wxyz = np.array(event.target.position), np.array(event.target.wxyz)
            drag.heard(phase)
            if phase == "update":
                await asyncio.to_thread(move, k, position, wxyz)

        return on_update

    def move_blade(self, j: int, position, wxyz=(1.0, 0.0, 0.0, 0.0)):
        """What dragging blade j's gizmo does: the blade moves there, no faster than 0.1 of the
        smallest element altitude per step (so that it skips no element), cutting as it goes."""
        with self.lock:
            self.scene.blades[j].move_to(
                self.sim.time,
                position,
                np.asarray(wxyz, float),
                0.1 * self.sim.model.min_altitude,
                self.sim.dt,
            )

    def move_tool(self, k: int, position, wxyz=(1.0, 0.0, 0.0, 0.0)):
        """What dragging tool k's gizmo does: the tool moves there over the next step."""
        with self.lock:
            self.sim.set_tool_pose(k, np.asarray(position, float), np.asarray(wxyz, float))

    # --- loops ----------------------------------------------------------------------------
    def _simulate(self):
        last = time.perf_counter()
        while not self.stop_event.is_set():
            now = time.perf_counter()
            wall = min(now - last, 0.05)
            last = now
            if not self.playing:
                time.sleep(0.01)
                continue
            with self.lock:
                dt = self.sim.solver.dt
                n = max(1, int(round(wall / dt)))
                t0 = time.perf_counter()
                try:
                    self.sim.run(steps=n)
                except PliantError as e:  # show it, pause; Reset starts again
                    self.error = str(e)
                    self.playing = False
                    self.play_button.label = "Play"
                    continue
                el = time.perf_counter() - t0
                if self.sim.model is not self._dt_model:  # a cut may have lowered the step
                    self.dt0 = self.sim.solver.dt * np.sqrt(max(1.0, float(self.stiffness.value)))
                    self._dt_model = self.sim.model
            self.steps_per_second = n / max(el, 1e-9)
            self.realtime_factor = self.steps_per_second * dt
            time.sleep(0.001)

    def _element_values(self, model) -> np.ndarray | None:
        """The colour field per element (von Mises stress [Pa], a membrane's larger principal
        tension [N/m] or body number), or None for the displacement (per node). Call under the lock."""
        if self.field == BODY_FIELD and model.bodies is not None:
            return np.asarray(model.bodies, dtype=float)
        if self.field == STRESS_FIELD:
            return model.element_results(self.sim.state)["von_mises"]
        if self.field == TENSION_FIELD:
            return model.membrane_results(self.sim.state)["max_tension"]
        return None

    @staticmethod
    def _surfaces(model) -> tuple:
        """(model, the surface drawn, membranes beside its tets or None)."""
        return model, _Surface.of_model(model), _Surface.sheets_beside(model.membrane_faces, model.tets)

    def draw(self):
        """Send the current surface, colours, status and tool forces to the browser."""
        with self.lock:
            model = self.sim.model  # after a cut, a new topology
            if self._surface[0] is not model:
                self._surface = self._surfaces(model)
            surface, sheets = self._surface[1], self._surface[2]
            P = self.sim.positions
            ev = self._element_values(model)
            u = self.sim.displacements
            t = self.sim.time
            tension = model.membrane_results(self.sim.state)["max_tension"] if sheets is not None else None
            forces = [self.sim.tool_force(k) for k in range(len(model.tools))]
            poses = [tool.pose(t) for tool in self.sim.solver.tools]
            blade_poses = [b.pose(t) for b in self.scene.blades]
            emb = self.sim.cutter.embedding if self.sim.cutter is not None else self.embedding
            held = len(self.sim.state.held) if model.tools else 0
            cuts = len(self.sim.cutter.events) if self.sim.cutter is not None else 0
        if emb is not None:  # the fine surface follows the tets
            V, F = emb.positions(model.tets, P), emb.faces
            vals = ev[emb.tet] if ev is not None else np.linalg.norm(emb.positions(model.tets, u), axis=1)
        else:
            V, F = P[surface.nodes], surface.faces
            vals = surface.node_values(ev) if ev is not None else np.linalg.norm(u[surface.nodes], axis=1)
        mesh, (lo, hi) = _coloured_mesh(V, F, vals, two_sided=emb is None and surface.sheet)
        self.server.scene.add_mesh_trimesh("/body", mesh)
        self.status.content = (
            f"t = {t:.3f} s · {self.steps_per_second:,.0f} steps/s · "
            f"real-time factor {self.realtime_factor:.2f}"
            + (f" · {cuts} cuts, {model.n_nodes:,} nodes" if self.scene.blades else "")
            + (f" · {held} nodes held" if held else "")
            + (f"  \n**stopped:** {self.error}" if self.error else "")
        )
        self.colourbar.content = f"{self.field}: {lo:.3g} (dark blue) … {hi:.3g} (yellow)"
        if sheets is not None:  # membranes beside the solid: their tension, or the displacement
            by_tension = self.field != DISPLACEMENT_FIELD
            sv = sheets.node_values(tension) if by_tension else np.linalg.norm(u[sheets.nodes], axis=1)
            sheet_mesh, (slo, shi) = _coloured_mesh(P[sheets.nodes], sheets.faces, sv, two_sided=True)
            self.server.scene.add_mesh_trimesh("/sheets", sheet_mesh)
            shown = TENSION_FIELD if by_tension else DISPLACEMENT_FIELD
            self.colourbar.content += f"  \nsheets beside it, {shown}: {slo:.3g} … {shi:.3g}"
        lines = []
        ext = float(np.ptp(self.model.reference_positions, axis=0).max())
        for k, ((f, _), (R, p)) in enumerate(zip(forces, poses)):
            ctrl = self.controls[k]
            q = quat_from_matrix(R)
            if ctrl is not None and self._drags[k].follows(p, q):
                ctrl.position, ctrl.wxyz = tuple(p), tuple(q)  # follow keyframes
            lines.append(f"tool {k} ({model.tools[k].name}): |F| = {np.linalg.norm(f):.3g} N")
            fmax = max(np.linalg.norm(f), 1e-12)
            seg = np.array([[p, p + 0.3 * ext * f / fmax]])
            self.server.scene.add_line_segments(
                f"/forces/{k}", seg, (255, 60, 60), thickness=3, thickness_units="screen"
            )
        self.force_text.content = "  \n".join(lines)
        for j, (R, p) in enumerate(blade_poses):
            q = quat_from_matrix(R)
            if self._blade_drags[j].follows(p, q):
                ctrl = self.blade_controls[j]
                ctrl.position, ctrl.wxyz = tuple(p), tuple(q)  # follow keyframes

    def serve(self, duration: float | None = None):
        """Run the simulation thread and the drawing loop (until Ctrl-C, :meth:`stop` or
        ``duration`` [s])."""
        sim_thread = threading.Thread(target=self._simulate, daemon=True)
        sim_thread.start()
        end = None if duration is None else time.perf_counter() + duration
        try:
            while not self.stop_event.is_set() and (end is None or time.perf_counter() < end):
                self.draw()
                time.sleep(0.05)
        finally:
            self.stop_event.set()
            sim_thread.join(timeout=2)

    def stop(self):
        self.stop_event.set()
        self.server.stop()


class PlaybackViewer:
    """Play back a results folder (OUTDIR/result.pvd) with a time slider."""

    def __init__(self, out_dir, host: str = "127.0.0.1", port: int = 8080):
        import re

        out = Path(out_dir)
        pvd = out / INDEX
        problem = file_problem(pvd)
        if problem == MISSING:
            raise InputError(f"{out}: no {INDEX} (not a pliant results folder)")
        if problem:
            raise InputError(f"{pvd}: {problem}")
        entries = re.findall(
            r'timestep="([^"]+)"[^>]*file="([^"/\\]+)"', pvd.read_text(encoding="utf-8", errors="replace")
        )
        if not entries:
            raise InputError(f"{pvd}: no frames")
        try:
            self.times = [float(t) for t, _ in entries]
        except ValueError:
            raise InputError(f"{pvd}: a timestep is not a number") from None
        self.files = [out / f for _, f in entries]
        missing = [f for f in self.files if not f.is_file()]
        if missing:
            raise InputError(f"{pvd}: lists {missing[0].name}, which is not in {out}")
        first = read_meshio(self.files[0], "result frame")
        self._cells, self._kind = np.empty((0, 4), np.int64), ""  # none shown yet
        self.sheets: _Surface | None = None  # membranes beside the tets
        self.X = first.points
        self._frame_cells(first, self.files[0])  # of the frame shown (frames after a cut differ)
        self.server = serve_on(host, port)
        _frame_camera(self.server, self.X)
        self.slider = self.server.gui.add_slider("frame", 0, len(self.files) - 1, 1, 0)
        self.label = self.server.gui.add_markdown("")
        self.slider.on_update(self._on_slider)
        self.show(0)

    def _on_slider(self, _event) -> None:
        self.shown(int(self.slider.value))

    def shown(self, i: int) -> bool:
        """show(i) for the slider: a frame that cannot be read (damaged or replaced since the viewer
        opened the folder) is named in the label instead of raising in the server's thread, and
        the last good frame stays on screen. Returns whether frame i is shown."""
        try:
            self.show(i)
        except (InputError, ValueError) as e:
            self.label.content = f"**frame {i + 1}/{len(self.files)} cannot be shown**: {e}"
            return False
        return True

    def _frame_cells(self, m, path: Path) -> str:
        """The frame's cell kind ("tetra", or "triangle" for membranes alone) after taking its
        surface where its topology differs from the frame shown last (a cut)."""
        kind = next((k for k in ("tetra", "triangle") if k in m.cells_dict), None)
        if kind is None:
            raise InputError(f"{path}: no tetrahedra or triangles; expected a pliant result frame")
        cells = m.cells_dict[kind]
        if kind != self._kind or len(m.points) != len(self.X) or not np.array_equal(cells, self._cells):
            self._kind, self._cells, self.X = kind, cells, m.points
            self.surface = _Surface.of_tets(cells) if kind == "tetra" else _Surface.of_sheet(cells)
            self.sheets = (
                _Surface.sheets_beside(m.cells_dict["triangle"], cells)
                if kind == "tetra" and "triangle" in m.cells_dict
                else None
            )
        return kind

    def show(self, i: int):
        """Frame i on the surface, coloured by the tets' von Mises stress [Pa] (membranes alone:
        their larger principal tension [N/m]; frames without either: the displacement [m])."""
        m = read_meshio(self.files[i], "result frame")
        kind = self._frame_cells(m, self.files[i])
        u = m.point_data.get("displacement", np.zeros_like(m.points))
        field, what = (
            ("von_mises", "von Mises [Pa]") if kind == "tetra" else ("membrane_max_tension", "tension [N/m]")
        )
        ev = m.cell_data_dict.get(field, {}).get(kind)
        if ev is None:
            vals, what = np.linalg.norm(u[self.surface.nodes], axis=1), "displacement [m]"
        else:
            vals = self.surface.node_values(ev)
        V = (m.points + u)[self.surface.nodes]
        mesh, (lo, hi) = _coloured_mesh(V, self.surface.faces, vals, self.surface.sheet)
        self.server.scene.add_mesh_trimesh("/body", mesh)
        self.label.content = (
            f"t = {self.times[i]:.4g} s (frame {i + 1}/{len(self.files)}); {what} {lo:.3g} … {hi:.3g}"
        )
        if self.sheets is not None:  # membranes beside the solid: their tension
            st = m.cell_data_dict.get("membrane_max_tension", {}).get("triangle")
            sheets = self.sheets
            sv = sheets.node_values(st) if st is not None else np.linalg.norm(u[sheets.nodes], axis=1)
            sheet_mesh, (slo, shi) = _coloured_mesh((m.points + u)[sheets.nodes], sheets.faces, sv, True)
            self.server.scene.add_mesh_trimesh("/sheets", sheet_mesh)
            shown = "tension [N/m]" if st is not None else "displacement [m]"
            self.label.content += f"; sheets beside it, {shown} {slo:.3g} … {shi:.3g}"

    def serve(self, duration: float | None = None):
        end = None if duration is None else time.perf_counter() + duration
        while end is None or time.perf_counter() < end:
            time.sleep(0.1)
