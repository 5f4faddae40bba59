"""normalflow: geometric surface processing via normal maps (Tasdizen, Whitaker, Burchard & Osher 2003).

Meshes go in as numpy arrays (``vertices`` (n, 3), ``faces`` (m, 3)) or as :class:`Mesh` objects, and come
back as :class:`Mesh` objects whose ``vertices``, ``faces``, ``normals``, ``colors`` and ``texcoords`` are
numpy views of the result (no copy). Every call returns ``(result, report)``; the report is a dict with the
keys of the command line's ``--json``.

The keyword arguments of :func:`smooth`, :func:`remesh`, :func:`voxelize` and :func:`extract` are the options of
the command line (``--target-faces 20000`` is ``target_faces=20000``, ``--no-repair`` is ``repair=False``), from
the library's one table: the same defaults, checks and results as ``normalflow smooth``. Each function's
docstring lists them; :func:`options` too.

    >>> import normalflow as nf
    >>> mesh = nf.read_mesh("part.ply")
    >>> out, report = nf.smooth(mesh, target_faces=20000)
    >>> nf.write_mesh("part_smoothed.ply", out)

Long calls release the GIL; ``progress(stage, fraction)`` is called on the calling thread, and Ctrl-C
(KeyboardInterrupt), or an exception raised by the callback, stops the run at its next check and is raised.
"""
import json as _json

from . import _normalflow as _nf
from ._normalflow import (Cancelled, InvalidInput, IoError, Mesh, NumericalError, OutOfMemory, Volume,  # noqa: F401
                          __version__)

__all__ = ["Mesh", "Volume", "read_mesh", "write_mesh", "read_volume", "image_to_volume", "smooth", "remesh", "voxelize",
           "extract", "compare", "noise", "taubin", "options", "InvalidInput", "IoError", "NumericalError",
           "OutOfMemory", "Cancelled", "__version__"]


def _mesh_report(self):
    """What normalflow info reports of the mesh: counts, closed, manifold, components, defects, area, volume."""
    return _json.loads(self._report_json())


Mesh.report = _mesh_report


def _mesh(mesh_or_vertices, faces=None):
    if isinstance(mesh_or_vertices, Mesh):
        if faces is not None:
            raise TypeError("faces given with a Mesh")
        return mesh_or_vertices
    if faces is None:
        raise TypeError("expected a Mesh, or vertices and faces")
    return Mesh(mesh_or_vertices, faces)


def options(command="smooth"):
    """The keyword arguments of smooth, remesh, voxelize or extract with their defaults, ranges and help."""
    return _nf.keyword_help(command)


def read_mesh(path):
    """Reads OBJ, PLY, OFF, STL, glTF/GLB or Draco (.drc) as a Mesh."""
    return _nf.read_mesh(str(path))


def write_mesh(path, mesh, faces=None):
    """Writes a Mesh (or vertices, faces) by the path's extension; the file is written whole or not at all."""
    _nf.write_mesh(str(path), _mesh(mesh, faces))


def read_volume(path, iso=None, label=None, negate=False, voxel_size=0.0):
    """Reads .vdb, .nrrd, .nhdr, .nii or .nii.gz as a signed distance Volume (see normalflow smooth --iso, --label,
    --negate: a scalar image needs iso, a label map label; a binary mask needs neither)."""
    return _nf.read_volume(str(path), iso, label, negate, voxel_size)


def image_to_volume(values, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0), iso=None, label=None, negate=False,
                    voxel_size=0.0):
    """A dense image (a 3-D array indexed [i, j, k]) as a signed distance Volume: the surface where the value is iso
    (inside above it), of the voxels labelled label, or of a binary mask's foreground."""
    return _nf.image_to_volume(values, [float(s) for s in spacing], [float(o) for o in origin], iso, label, negate,
                               float(voxel_size))


_brick_workers = {}  # in a worker process: the BrickWorker of the run whose bricks it last ran


def _run_brick(run, context, job):
    """One brick of a bricked run, as a Dask task: the run's BrickWorker (its mesh's search built once per worker
    process) runs the job's message and returns the outcome's."""
    worker = _brick_workers.get(run)
    if worker is None:
        _brick_workers.clear()  # one run at a time per worker process: the last one's search goes
        worker = _brick_workers[run] = _nf.BrickWorker(context)
    return worker.run(job)


class _DaskBricks:
    """The bricks of a bricked run as tasks of a dask.distributed client: the run's context (its mesh, grid and
    options) goes to every worker once, each pass's bricks are submitted as their windows are cut (at most twice as
    many in flight as there are worker threads, so that the windows do not all wait in memory at once), and their
    outcomes are handed back in order. Dask is the scheduler; every worker must run this build of normalflow."""

    def __init__(self, client):
        self._client = client
        self._context = None
        self._scattered = None
        self._run = None

    def __call__(self, context, count, make, take):
        if self._context != context:
            import uuid
            self._context = context
            self._run = uuid.uuid4().hex
            self._scattered = self._client.scatter(context, broadcast=True, hash=False)
        threads = sum(w.get("nthreads", 1) for w in self._client.scheduler_info()["workers"].values())
        limit = 2 * max(1, threads)
        futures = {}
        submitted = 0
        for taken in range(count):
            while submitted < count and submitted - taken < limit:
                job = self._client.scatter(make(submitted), hash=False)  # the task runs where its window went
                futures[submitted] = self._client.submit(_run_brick, self._run, self._scattered, job, pure=False)
                submitted += 1
            take(futures.pop(taken).result())


def smooth(mesh, faces=None, *, progress=None, client=None, **options):
    """The whole pipeline (normalflow smooth): scan conversion, the normal map filtered on the surface and the
    volume refitted to it, then the result handed back. ``mesh`` is a Mesh, vertices with ``faces``, or a Volume
    (then ``volume=True`` returns the smoothed Volume instead of its surface).

    ``client``: a ``dask.distributed`` Client. A run in bricks (``brick_size``, or a volume over ``max_memory``)
    then runs its bricks as tasks on the cluster's workers, each holding the bricks it runs; this process holds
    the assembled volume and does the rest. The result is the one of the same run without ``client``, bit for bit.
    A run that fits whole runs here (its report's warnings say so).

    Returns (Mesh or Volume, report dict)."""
    if isinstance(mesh, Volume):
        if client is not None:
            raise TypeError("client= runs the bricks of a mesh's run; a Volume is smoothed here")
        want_volume = bool(options.pop("volume", False))
        out, report = _nf.smooth_volume(mesh, options, progress, not want_volume)
    else:
        out, report = _nf.smooth(_mesh(mesh, faces), options, progress, _bricks(client))
    return out, _json.loads(report)


def _bricks(client):
    return None if client is None else _DaskBricks(client)


def remesh(mesh, faces=None, *, progress=None, client=None, **options):
    """A closed manifold re-meshing of any mesh through its volume (normalflow remesh): the extraction's vertices
    moved onto the input's creases and corners (sharpen=False keeps them on the grid), decimated with target_faces
    or max_error. ``client`` as for :func:`smooth` (a remesh whose engine runs). Returns (Mesh, report dict)."""
    out, report = _nf.remesh(_mesh(mesh, faces), options, progress, _bricks(client))
    return out, _json.loads(report)


def voxelize(mesh, faces=None, *, progress=None, **options):
    """Scan conversion (normalflow voxelize): a narrow-band signed distance Volume of the mesh.

    Returns (Volume, report dict)."""
    volume, report = _nf.voxelize(_mesh(mesh, faces), options, progress)
    return volume, _json.loads(report)


def extract(volume, *, progress=None, **options):
    """The zero level set of a Volume as a closed manifold Mesh (normalflow extract), decimated with target_faces
    or max_error. Returns (Mesh, report dict)."""
    out, report = _nf.extract(volume, options, progress)
    return out, _json.loads(report)


def compare(reference, candidate, *, samples=None, seed=None, crease_angle=None, crease_radius=None,
            correspondence=False, self_intersections=True):
    """Compares a candidate with a reference without vertex correspondence (normalflow compare): distances both
    ways, normal angle, area, volume, crease preservation, topology. Each is a Mesh or a (vertices, faces) pair.

    Returns the report dict; its "candidates"[0] holds the candidate's figures."""
    d = _nf.COMPARE_DEFAULTS
    ref = reference if isinstance(reference, Mesh) else _mesh(*reference)
    cand = candidate if isinstance(candidate, Mesh) else _mesh(*candidate)
    return _json.loads(_nf.compare(ref, cand, d["samples"] if samples is None else samples,
                                   d["seed"] if seed is None else seed,
                                   d["crease_angle"] if crease_angle is None else crease_angle,
                                   d["crease_radius"] if crease_radius is None else crease_radius,
                                   correspondence, self_intersections))


def noise(mesh, faces=None, *, sigma=None, seed=None, kind="gaussian", direction="normal", fraction=None):
    """Synthetic noise (normalflow noise): sigma in mean edge lengths, deterministic for a seed.
    Returns (Mesh, report dict)."""
    d = _nf.NOISE_DEFAULTS
    out, report = _nf.noise(_mesh(mesh, faces), d["sigma"] if sigma is None else sigma,
                            d["seed"] if seed is None else seed, kind, direction,
                            d["fraction"] if fraction is None else fraction)
    return out, _json.loads(report)


def taubin(mesh, faces=None, *, iterations=None, lambda_=None, mu=None, fix_boundary=True, progress=None):
    """Taubin's lambda|mu smoothing (normalflow taubin), the mesh-side baseline. Returns (Mesh, report dict)."""
    if not hasattr(_nf, "taubin"):
        raise InvalidInput("taubin: this build has no OpenMesh (NORMALFLOW_WITH_OPENMESH=OFF)")
    d = _nf.TAUBIN_DEFAULTS
    out, report = _nf.taubin(_mesh(mesh, faces), d["iterations"] if iterations is None else iterations,
                             d["lambda_"] if lambda_ is None else lambda_, d["mu"] if mu is None else mu,
                             fix_boundary, progress)
    return out, _json.loads(report)


for _f in (smooth, remesh, voxelize, extract):  # each lists its keyword arguments, from the options table
    _f.__doc__ += "\n\n    Keyword arguments (None: the default):\n\n" + "".join(
        "    " + line + "\n" for line in _nf.keyword_help(_f.__name__).splitlines())
