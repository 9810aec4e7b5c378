"""Type stubs of the vclay extension module (python/src/*.rs)."""

from os import PathLike
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Path = Union[str, PathLike]
ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]
Mesh = Tuple[F64, npt.NDArray[np.uint32], F64]

class VclayError(Exception):
    """Base class of every vclay error; the message names the place (file, line, key, entity)."""
class FileError(VclayError):
    """A file could not be read, parsed or written (model JSON, meshes, .ovm, scenarios, sessions)."""
class GeometryError(VclayError):
    """Invalid geometry or parameters: knot vectors, weights, control nets, lattices, FFD solves."""
class PdeError(VclayError):
    """A PDE surface spec is invalid or its solve failed."""
class RenderError(VclayError):
    """A picture could not be made."""
class SessionError(VclayError):
    """A session error: an unknown model, nothing to undo or redo, a model that failed."""
class CommandError(SessionError):
    """A command could not apply; the session is unchanged."""
class DivergedError(SessionError):
    """The simulation diverged; the model keeps its last good state."""
class ArgumentError(VclayError, ValueError):
    """An argument's value is out of range or unknown; the message names the argument."""
class MemoryLimitError(VclayError, MemoryError):
    """Work over the memory limit (`set_max_memory`), raised before anything is allocated."""

DEFAULT_MAX_MEMORY: int
def set_max_memory(nbytes: Optional[int] = None) -> None:
    """The most memory (bytes) one call may ask for; None restores DEFAULT_MAX_MEMORY (4 GiB)."""
def max_memory() -> int:
    """The memory limit in bytes."""

class Entity:
    """A NURBS curve, surface or volume."""
    @property
    def kind(self) -> str:
        """`"nurbs-curve"`, `"nurbs-surface"` or `"nurbs-volume"`."""
    @property
    def name(self) -> Optional[str]:
        """The entity's name in its file (or None)."""
    @property
    def param_dims(self) -> int:
        """Number of parameters: 1, 2 or 3."""
    @property
    def degree(self) -> list[int]:
        """Degree per parametric axis, as a tuple."""
    @property
    def knots(self) -> list[F64]:
        """Knot vectors, one float64 array per parametric axis."""
    @property
    def control_points(self) -> F64:
        """Control points (n, 3), (nu, nv, 3) or (nu, nv, nw, 3) (a copy); assign an array of
        the same shape (finite) to replace them."""
    @control_points.setter
    def control_points(self, value: ArrayLike) -> None: ...
    @property
    def weights(self) -> F64:
        """Weights, the control net's shape (a copy); assign positive finite ones to replace."""
    @weights.setter
    def weights(self, value: ArrayLike) -> None: ...
    @property
    def domain(self) -> list[Tuple[float, float]]:
        """Parameter domain per axis: a list of `(min, max)`."""
    def evaluate(self, params: ArrayLike) -> F64:
        """Points (n, 3) at an (n, d) parameter array."""
    def point(self, u: float, v: Optional[float] = None, w: Optional[float] = None) -> Tuple[float, float, float]:
        """One point: `point(u)`, `point(u, v)` or `point(u, v, w)` as a tuple `(x, y, z)` (the
        low-overhead call for single points)."""
    def derivatives(self, params: ArrayLike, order: int) -> F64:
        """Partial derivatives up to `order` at an `(n, d)` parameter array. Curves: `(n, order+1,
        3)`, `[:, k]` = d^k C/du^k. Surfaces: `(n, order+1, order+1, 3)`, `[:, a, b]` =
        d^(a+b) S / du^a dv^b (zero where a + b > order). Volumes: `(n, o+1, o+1, o+1, 3)` the
        same way. Index 0 is the point itself."""
    def evaluate_grid(self, u: ArrayLike, v: ArrayLike, out: Optional[F64] = None) -> F64:
        """Surfaces: points on the grid u x v, shape (len(u), len(v), 3); written into `out`
        (C-contiguous float64 of that shape, returned) when given."""
    def insert_knot(self, value: float, times: int = 1, axis: int = 0) -> "Entity":
        """A new entity with `value` inserted `times` times into the knot vector of `axis`
        (Piegl & Tiller A5.1); the shape is unchanged."""
    def elevate_degree(self, times: int = 1, axis: int = 0) -> "Entity":
        """A new entity with the degree along `axis` raised by `times` (Piegl & Tiller A5.9); the
        shape is unchanged."""
    def tessellate(self, samples: int = 32) -> Mesh:
        """Surfaces and volume boundaries as triangles: `(vertices (n, 3), triangles (m, 3) uint32,
        normals (n, 3))`, `samples` per parametric axis."""
    def to_dict(self) -> dict[str, Any]:
        """The entity as a dict of the vclay model JSON format (`docs/formats.md`)."""

class Curve(Entity):
    """A NURBS curve `C(u) = sum N_i,p(u) w_i P_i / sum N_i,p(u) w_i` (`d-nurbs.txt` eq 1)."""
    def __init__(self, degree: int, knots: ArrayLike, control_points: ArrayLike, weights: Optional[ArrayLike] = None, name: Optional[str] = None) -> None: ...

class Surface(Entity):
    """A tensor-product NURBS surface `S(u, v)`."""
    def __init__(self, degree: Sequence[int], knots: Sequence[ArrayLike], control_points: ArrayLike, weights: Optional[ArrayLike] = None, name: Optional[str] = None) -> None: ...

class Volume(Entity):
    """A trivariate NURBS volume `V(u, v, w)` (FFD lattices and B-spline solids are volumes)."""
    def __init__(self, degree: Sequence[int], knots: Sequence[ArrayLike], control_points: ArrayLike, weights: Optional[ArrayLike] = None, name: Optional[str] = None) -> None: ...

def load(path: Path) -> list[Entity]:
    """The entities of a model file, recognized by content: vclay or geomdl JSON, STEP, IGES,
    or a lattice .ovm (its boundary limit surface as bicubic patches)."""
def load_part(path: Path) -> "Part":
    """The trimmed shells of a CAD file (STEP B-rep, IGES 144/142 or 186, or a model JSON with
    "shells") as a `Part`; a file without trimmed faces raises FileError (use load)."""
class Part:
    """A CAD part of trimmed faces: exact surfaces, shared edges, loops and pcurves. Pickles
    exactly. Open the file with vclay.open to sculpt a face (kind cad-part)."""
    @property
    def entities(self) -> list[Entity]:
        """The part's Curve/Surface entities (a face's "entity" indexes this list)."""
    @staticmethod
    def from_json(text: str) -> "Part":
        """A part from the model JSON text that to_json writes."""
    def to_json(self) -> str:
        """The part as model JSON text (docs/formats.md section 1)."""
    def shell_count(self) -> int:
        """How many shells the part has."""
    def closed(self, shell: int = 0) -> bool:
        """Whether every edge of the shell is used by two faces in opposite directions."""
    def faces(self, shell: int = 0) -> list[dict[str, Any]]:
        """Each face: surface, entity, same_sense, loops ((n, 2) arrays of (u, v): the outer
        loop then the holes, 33 samples per pcurve) and edges ((edge, forward) uses per loop; a
        pole is (-1 - vertex, True))."""
    def edges(self, shell: int = 0) -> list[Entity]:
        """The shell's edges as exact 3D curves."""
    def mesh(self, shell: int = 0, samples: int = 32) -> tuple[F64, npt.NDArray[np.uint32], F64, npt.NDArray[np.uint32]]:
        """(vertices, triangles, normals, faces): the shell meshed with its trims, crack-free;
        faces[t] is the face of triangle t."""
    def save(self, path: Path, samples: int = 32) -> None:
        """Writes .step/.stp (solids as MANIFOLD_SOLID_BREP), .igs/.iges, .json (with shells),
        or the shells meshed (.obj, .stl, .ply, .glb)."""
def save(path: Path, entities: Sequence[Entity], samples: int = 48) -> None:
    """`save(path, entities, samples=48)`: writes entities in the format the extension names:
    `.json` (vclay model), `.geomdl.json`, `.step`/`.stp`, `.igs`/`.iges`, or a tessellated mesh
    (`.obj`, `.stl`, `.ply`, `.glb`; curves left out). Writes are atomic."""
def convert(input: Path, output: Path, samples: int = 48) -> None:
    """Like `vclay convert`: reads what load and read_mesh read (STEP faces trimmed) and writes
    the format the output's extension names (.json, .geomdl.json, .step, .igs, .obj, .stl,
    .ply, .glb)."""
def read_mesh(path: Path) -> Mesh:
    """An OBJ/STL/PLY/glb mesh, a .vtu lattice's boundary or a triangular NURBS file (meshed)."""
def write_mesh(path: Path, vertices: ArrayLike, triangles: ArrayLike) -> None:
    """`write_mesh(path, vertices, triangles)`: writes an OBJ/STL/PLY/glb mesh (normals computed)."""
def fit_surface(points: ArrayLike, grid: Tuple[int, int] = (32, 32), degree: int = 3, fairness: Tuple[float, float] = (0.0, 1e-9), robust: Optional[str] = "auto", weights: bool = False, corrections: int = 2) -> Tuple["Surface", dict]:
    """A surface fitted to an (n, 3) point cloud (D-NURBS fairness); (surface, report)."""
def render(source: Union[Path, Sequence[Entity], Tuple[ArrayLike, ArrayLike]], out: Path, size: Tuple[int, int] = (640, 480), view: str = "iso", wireframe: bool = False, ortho: bool = False) -> None:
    """`render(source, out, size=(640, 480), view="iso", wireframe=False, ortho=False)`: writes a
    PNG. `source` is a model or mesh file path, a list of entities, or a `(vertices,
    triangles)` pair. `view` is `iso`, `front`, `top` or `side`; `wireframe` adds control nets
    (meshes: triangle edges)."""

class Ffd:
    """A trivariate NURBS lattice over a box, the identity at rest: `Q(u, v, w)` with control
    points at the Greville abscissae. Moving points of space (direct manipulation) moves the
    control points by the least-norm displacement field (eqs 7, 12); `deform` maps points."""
    def __init__(self, lo: Sequence[float], hi: Sequence[float], degree: int = 3, control_points: Union[int, Sequence[int], None] = None) -> None: ...
    @staticmethod
    def enclosing(points: ArrayLike, degree: int = 3, control_points: Union[int, Sequence[int], None] = None, margin: float = 0.05) -> "Ffd":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    @property
    def dims(self) -> list[int]:
        """Control points per axis."""
    @property
    def bounds(self) -> Tuple[list[float], list[float]]:
        """The box `(lo, hi)`."""
    @property
    def control_points(self) -> F64:
        """Current control points (nu, nv, nw, 3); assignable."""
    @control_points.setter
    def control_points(self, value: ArrayLike) -> None: ...
    @property
    def weights(self) -> F64:
        """Weights (nu, nv, nw); assignable (positive, finite)."""
    @weights.setter
    def weights(self, value: ArrayLike) -> None: ...
    def parameters(self, points: ArrayLike) -> F64:
        """Parameters `(n, 3)` in `[0, 1]^3` of rest-space points `(n, 3)` (the linear map of
        section 2); a point outside the box raises `GeometryError`."""
    def deform(self, points: ArrayLike) -> F64:
        """Where the deformation takes rest-space points: an `(n, 3)` array to an `(n, 3)` array
        (`Q(u(x), v(x), w(x))` inside the box, `x` itself outside). In parallel, GIL released."""
    def move_point(self, source: Sequence[float], target: Sequence[float]) -> None:
        """Direct manipulation of one point (eq 7): the rest-space point `source` goes to
        `target`. Afterwards `deform([source])` is `target`."""
    def move_points(self, sources: ArrayLike, targets: ArrayLike, least_squares: bool = False) -> None:
        """Direct manipulation of many points at once (eq 12): rest-space `sources` `(m, 3)` go to
        `targets` `(m, 3)` by the least-norm displacement. Conflicting constraints raise
        `GeometryError` naming them unless `least_squares=True`."""
    def reset(self) -> None:
        """Back to the rest lattice."""
    def volume(self) -> Volume:
        """The lattice as a `Volume` (current control points and weights)."""

class Lattice:
    """A polyhedral cell complex (points, edges, faces, cells), validated on construction: the
    control or subdivided lattice of a subdivision solid."""
    @staticmethod
    def primitive(spec: str) -> "Lattice":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    @staticmethod
    def read(path: Path) -> "Lattice":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    def write(self, path: Path) -> None:
        """Writes the lattice (`.ovm`, `.vtu`) or its boundary surface (`.obj`, `.ply`, `.stl`)."""
    def to_ovm(self) -> str:
        """The lattice as `.ovm` text (points written exactly: `from_ovm` reads the same bits)."""
    @staticmethod
    def from_ovm(text: str) -> "Lattice":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    def subdivide(self, levels: int = 1, boundary: str = "sharp") -> "Lattice":
        """`levels` MacCracken-Joy subdivision steps with the boundary rule `"interior"`,
        `"smooth"` or `"sharp"`: a new lattice. Refused above 50 million predicted cells."""
    def stats(self) -> dict[str, int]:
        """Counts and checks as a dict: points, edges, faces, cells, boundary_faces and
        inverted_cells (cells of non-positive signed volume)."""
    @property
    def points(self) -> F64:
        """The points, `(n, 3)` (a copy)."""
    @property
    def edges(self) -> npt.NDArray[np.int64]:
        """Edges as a `(m, 2)` int64 array of point indices (numpy's index type, as
        `np.argsort` gives)."""
    def with_points(self, points: ArrayLike) -> "Lattice":
        """A lattice of the same topology with new points `(n, 3)`."""
    def boundary(self) -> Mesh:
        """The outward boundary surface: `(vertices, triangles, normals)`."""
    def __len__(self) -> int: ...

class PdeSurface:
    """A PDE surface model: one or more patches from a spec (dict or JSON text; errors name the
    place in the spec: `PdeError`)."""
    def __init__(self, spec: Union[dict[str, Any], str]) -> None: ...
    @staticmethod
    def read(path: Path) -> "PdeSurface":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    @staticmethod
    def from_toml(text: str) -> "PdeSurface":
        """staticmethod(function) -> method

        Convert a function to be a static method.

        A static method does not receive an implicit first argument.
        To declare a static method, use this idiom:

             class C:
                 @staticmethod
                 def f(arg1, arg2, argN):
                     ...

        It can be called either on the class (e.g. C.f()) or on an instance
        (e.g. C().f()). Both the class and the instance are ignored, and
        neither is passed implicitly as the first argument to the method.

        Static methods in Python are similar to those found in Java or C++.
        For a more advanced concept, see the classmethod builtin."""
    @property
    def patches(self) -> list[str]:
        """Patch names, in order."""
    def evaluate(self, params: ArrayLike, t: float = 0.0, patch: int = 0) -> F64:
        """Points of patch `patch` at time `t` for an `(n, 2)` array of `(u, v)`: `(n, 3)`."""
    def mesh(self, t: float = 0.0, grid: Tuple[int, int] = (64, 64)) -> Mesh:
        """Every patch at time `t` tessellated on `grid = (nu, nv)` samples: `(vertices, triangles,
        normals)`."""
    def residual(self, t: float = 0.0) -> float:
        """Largest root-mean-square collocation residual over the patches at time `t`."""
    def residual_check(self, t: float = 0.0) -> dict[str, Any]:
        """The residual against the surface's size: `residual_rms`, `size` (bounding-box
        diagonal), `ratio` and `warning` (a sentence when `ratio` is over 1 %, else None)."""
    def __len__(self) -> int: ...

class Session:
    """A session: named models of any kind (D-NURBS, subdivision and B-spline solids, FFD, PDE
    surfaces), their scheduled commands, the command log, undo and redo.

    Threads: every method locks the session; a call from another thread while one runs (a
    `step` in a worker thread, `energy()` from a monitor) waits for it without holding the GIL
    (a long `step` lets others in between its chunks of about 20 ms), so no call fails with
    "Already mutably borrowed"."""
    def __init__(self) -> None: ...
    @staticmethod
    def from_toml(text: str, base: Path = ".") -> "Session":
        """A scenario given as a string; relative files resolve against `base`."""
    @staticmethod
    def load(path: Path) -> "Session":
        """The same as vclay.open(path)."""
    def save(self, path: Path) -> None:
        """Writes the session (every model's full state, the schedule, the command log) to a
        `.json` session file, atomically. Loading it and stepping continues bit for bit."""
    def to_dict(self) -> dict[str, Any]:
        """The session file's content as a dict."""
    @staticmethod
    def from_dict(d: dict[str, Any]) -> "Session":
        """The session `to_dict` gave; continues bit for bit."""
    @property
    def models(self) -> list[str]:
        """Model names, in order."""
    @property
    def time(self) -> float:
        """Session time: the earliest model clock."""
    @property
    def scenario_steps(self) -> Optional[int]:
        """The scenario's run length in steps (None for a session without run information)."""
    def steps(self, model: Optional[str] = None) -> int:
        """Steps taken by model `model` (default: the first)."""
    def kind(self, model: Optional[str] = None) -> str:
        """`kind` of model `model`: `dnurbs-curve`, `subdivision-solid`, ..."""
    def tools(self, model: Optional[str] = None) -> list[dict[str, Any]]:
        """The edits the model takes: action, acts_on, keys (name, value, unit, min, max,
        required, help), help."""
    def summary(self, model: Optional[str] = None) -> str:
        """One line about model `model` (sizes)."""
    def apply(self, command: Union[dict[str, Any], str]) -> str:
        """Applies a command now: a dict (or JSON text) such as `{"action": "rope", "from": [1, 1,
        1], "to": [1.5, 1.4, 1.6], "until": 0.5}` or `{"action": "set", "name":
        "edge_stiffness", "value": 80}`, optionally with `"model": name`. Returns the log line.
        A command that cannot apply raises `CommandError` and leaves the session unchanged."""
    def schedule(self, commands: Sequence[dict[str, Any]]) -> None:
        """Schedules commands (dicts with `"at"`: seconds) like a scenario's timeline."""
    def undo(self) -> dict[str, Any]:
        """Undoes the last command; returns its log entry as a dict."""
    def redo(self) -> str:
        """Applies the last undone command again; returns its log line."""
    @property
    def can_undo(self) -> bool:
        """Whether there is something to undo."""
    @property
    def can_redo(self) -> bool:
        """Whether there is something to redo."""
    def step(self, n: int = 1, *, progress: Optional[Callable[[int, int], Any]] = None) -> list[str]:
        """Advances every model n steps without the GIL, in chunks of about 20 ms: Ctrl-C
        raises KeyboardInterrupt between chunks (steps done stay done), progress(done, n) is
        called at most every 0.1 s and at the end."""
    def advance_to(self, t: float) -> list[str]:
        """Steps each model until its clock reaches `t` (within half a step)."""
    def run(self, out_dir: Path, steps: Optional[int] = None) -> dict[str, Any]:
        """Runs `steps` steps (default: the rest of the scenario) writing the scenario's
        `[output]` (frames, final files, energy table) into `out_dir`, like `vclay run`.
        Returns a dict: steps, mean_step_ms, frames, files, log."""
    def energy(self, model: Optional[str] = None) -> dict[str, float]:
        """Energies of model `model` as a dict: `kinetic` (1/2 v^T M v), `elastic` (the internal
        energy of the deformation: springs or the metric-tensor energy of solids, the thin-plate
        under tension energy of D-NURBS), `tools` (energy stored in tools: the springs of ropes
        and data points), and `total` = kinetic + elastic + tools, so the parts add up to it.

        D-NURBS count a rope's spring at its material point and a data point's at the nearest
        point (`vclay_dynamics::dnurbs::spring_energy`). The command line's energy table
        (`vclay run`, per step) keeps D-NURBS `tools` at 0 and `total` = kinetic + elastic."""
    def params(self, model: Optional[str] = None) -> list[dict[str, Any]]:
        """Material and simulation parameters of model `model`: a list of dicts (name, value,
        min, max, doc); change one with `apply({"action": "set", "name": ..., "value": ...})`."""
    @property
    def log(self) -> list[dict[str, Any]]:
        """The command log: a list of dicts (step, time, model, command, message)."""
    def state(self, model: Optional[str] = None) -> dict[str, Any]:
        """Everything model `model` saves (its session-file entry) as a dict."""
    def control_points(self, model: Optional[str] = None) -> F64:
        """Control points in the net's shape, as Entity.control_points ((nu, nv, 3) for a
        D-NURBS surface, (nu, nv, nw, 3) for FFD and B-spline solids); (n, 3) for subdivision
        lattices."""
    def weights(self, model: Optional[str] = None) -> F64:
        """NURBS weights in the net's shape (SessionError for kinds without them)."""
    def set_control_points(self, points: ArrayLike, model: Optional[str] = None) -> int:
        """Moves the control points (one undoable group of move-point edits); returns how many moved."""
    def set_weights(self, weights: ArrayLike, model: Optional[str] = None) -> int:
        """Sets the weights (one undoable group of set-weight edits); returns how many changed."""
    def surface(self, model: Optional[str] = None) -> Surface:
        """The model's current geometry as a Surface (D-NURBS surfaces)."""
    def entities(self, model: Optional[str] = None) -> list[Entity]:
        """The model's current exact geometry (empty for kinds without tensor-product NURBS)."""
    def data_points(self, model: Optional[str] = None) -> F64:
        """Data points of model `model`, `(n, 3)`: a solid's data (finest) lattice points; for the
        other kinds the vertices of the display mesh (curves: the display polyline)."""
    def mesh(self, model: Optional[str] = None) -> Mesh:
        """The display surface of model `model`: `(vertices, triangles, normals)`."""
    def export(self, path: Path, model: Optional[str] = None) -> None:
        """Writes model `model` to `path` in the format its extension names (`.json`, `.obj`,
        `.ply`, `.stl`, `.vtu`, `.ovm`, `.glb`, `.step`, `.igs`, as the kind supports)."""
    def add(self, name: str, source: "Session", model: Optional[str] = None) -> None:
        """`add(name, source, model=None)`: a copy of model `model` of session `source` (its
        current state, material and tools; not its scheduled commands) added to this session
        under `name`: how an empty `Session()` is filled, or models of several files are put
        side by side. A name already in use raises `SessionError`."""
    def __len__(self) -> int: ...
    def __iter__(self) -> Any: ...
    def __contains__(self, name: str) -> bool: ...

def open(path: Path) -> Session:
    """Any file vclay reads, recognized by content, as a Session: scenario, saved session,
    model file (JSON, STEP, IGES), PDE spec, triangular model, lattice (.ovm, .vtu) or mesh.
    A point cloud or geomdl document raises FileError naming what takes it."""

def dnurbs_surface(points: Union[ArrayLike, Surface], degree: Tuple[int, int] = (3, 3), weights: Optional[ArrayLike] = None, knots: Optional[Sequence[ArrayLike]] = None, *, material: Optional[dict[str, Union[float, str]]] = None, dt: Optional[float] = None, engine: Optional[str] = None, dynamic_weights: Optional[bool] = None, reference: Optional[str] = None, fix: Optional[Sequence[int]] = None, name: Optional[str] = None) -> Session:
    """A D-NURBS surface session from a control net (nu, nv, 3) or a Surface. material: preset,
    mu, gamma, alpha, beta; dt (or the preset's); engine "generalized" | "frozen"; reference
    "rest" | "absolute". Fit points with session.apply({"action": "data", "points": ...})."""

def clay(mesh: Union[Path, Tuple[ArrayLike, ArrayLike]], cells: int = 500, level: int = 2, *, dt: Optional[float] = None, name: Optional[str] = None) -> Session:
    """A closed mesh (file or (vertices, triangles)) as a dynamic subdivision solid session
    (virtual clay): about `cells` control cells, boundary fitted at level `level`."""
