r"""
Ensemble results on disk: a labelled xarray Dataset in a Zarr store, written chunk by chunk.

The layout (what :func:`open_ensemble` returns)::

    dims:   body (N), time (n samples), component (x, y, z), angle (phi, psi, theta),
            quaternion_component (w, x, y, z), chunk (the run's chunks of bodies)
    coords: body (0 ... N-1), time [yr], component, angle, quaternion_component
    omega       (body, time, component)            angular velocity [rad/yr], body axes
    euler       (body, time, angle)                the paper's Euler angles [rad] (optional)
    quaternion  (body, time, quaternion_component) attitude, body -> orbital, scalar first
    jacobi      (body, time)                       Jacobi integral [I rad^2/yr^2]
    status      (body) int8                        0 pending, 1 succeeded, 2 failed
    reason      (body) str                         why a failed body failed ('' otherwise)
    n_steps, nfev (body)                           integration steps, torque evaluations
    omega0 (body, component), euler0 (body, angle) the body's initial state [rad/yr], [rad]
    n_impacts   (body)                             the body's number of impacts
    chunk_done  (chunk) bool                       chunk written completely
    attrs: the scenario (a ROS 2 parameters file), the per-body inputs, N, chunk size, ...

A run may leave out the variables of :data:`OPTIONAL_VARIABLES` (``euler``: a run without Euler
angles): the store then has no such array, and ``attrs['left_out']`` maps each to how the run
left it out; reading it (:meth:`EnsembleStore.read`, :func:`ensemble_variable`) raises an
:class:`EnsembleStoreError` saying so. A store without that attribute has every variable.

Rows of a failed body after its last good sample are NaN; rows of a pending body (a chunk not
written yet) read as NaN with status 0. The store is Zarr format 2 (every Zarr and xarray
reader opens it; the body axis is chunked as the run's chunks, the other axes whole). It is
created once with its full shape (metadata only), then each chunk of bodies is written into
its own region as its task finishes, and only then marked in ``chunk_done``: a run
interrupted at any point leaves complete chunks marked and the others not, and a restart
writes the unmarked ones again (``tumble_ros.ensembles.run_ensemble_to_store``). Memory
never holds more than the chunks being written. This module knows nothing of the physics: it
stores the arrays it is given (``tumble_ros.io`` does not import ``tumble_ros.core``).
"""
from __future__ import annotations

from contextlib import contextmanager
import errno
import fcntl
import json
import os
from pathlib import Path
import shutil
import socket
import time
from typing import Any, Collection, Iterable, Iterator, Mapping, TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from tumble_ros.errors import IoError

if TYPE_CHECKING:  # (xarray is imported where it is used: io users without it load this module)
    import xarray

__all__ = ['EnsembleStore', 'EnsembleStoreError', 'EnsembleStoreLocked', 'ensemble_variable',
           'lock_path', 'open_ensemble', 'store_lock', 'STATUS_FAILED', 'STATUS_PENDING',
           'STATUS_SUCCEEDED', 'REASON_WIDTH', 'SCENARIO_ATTR', 'LEFT_OUT_ATTR',
           'OPTIONAL_VARIABLES']

FORMAT = 'tumble_ros ensemble'
FORMAT_VERSION = 1
STATUS_PENDING, STATUS_SUCCEEDED, STATUS_FAILED = 0, 1, 2
#: The attribute holding the run's scenario (the text of a ROS 2 parameters file).
SCENARIO_ATTR = 'scenario'
#: Longest stored failure reason [characters] (longer ones are cut, ending with '...').
REASON_WIDTH = 160
#: The attribute mapping each variable a run left out to how it was left out (absent: none).
LEFT_OUT_ATTR = 'left_out'

#: name -> (dims, dtype, attrs) of the per-body variables.
VARIABLES = {
    'omega': (('body', 'time', 'component'), 'f8',
              {'long_name': 'angular velocity', 'units': 'rad/yr',
               'frame': 'body principal axes'}),
    'euler': (('body', 'time', 'angle'), 'f8',
              {'long_name': "the paper's Euler angles (phi, psi, theta), z-x-z",
               'units': 'rad', 'note': 'phi and psi continuous (not wrapped)'}),
    'quaternion': (('body', 'time', 'quaternion_component'), 'f8',
                   {'long_name': 'attitude quaternion, scalar first, body -> orbital frame',
                    'units': '1'}),
    'jacobi': (('body', 'time'), 'f8',
               {'long_name': 'Jacobi integral (constant between impacts)',
                'units': 'I rad^2/yr^2 (inertia normalised)'}),
    'status': (('body',), 'i1',
               {'long_name': 'integration status', 'flag_values': [0, 1, 2],
                'flag_meanings': 'pending succeeded failed'}),
    'reason': (('body',), f'<U{REASON_WIDTH}',
               {'long_name': 'why the body failed (empty when it succeeded)'}),
    'n_steps': (('body',), 'i8', {'long_name': 'integration steps'}),
    'nfev': (('body',), 'i8', {'long_name': 'torque (right-hand side) evaluations'}),
    'omega0': (('body', 'component'), 'f8',
               {'long_name': 'initial angular velocity', 'units': 'rad/yr',
                'frame': 'body principal axes'}),
    'euler0': (('body', 'angle'), 'f8',
               {'long_name': 'initial Euler angles (phi, psi, theta)', 'units': 'rad'}),
    'n_impacts': (('body',), 'i4', {'long_name': 'number of impacts on the body'}),
}
#: The variables a run may leave out (:meth:`EnsembleStore.create`'s ``left_out``).
OPTIONAL_VARIABLES = ('euler',)


class EnsembleStoreError(IoError):
    """An ensemble store that cannot be created, opened or resumed."""


class EnsembleStoreLocked(EnsembleStoreError):
    """An ensemble store that another live run is writing (its lock file names it)."""


def lock_path(path: str | Path) -> Path:
    """Return the lock file of the store at ``path``: ``X.zarr.lock`` beside ``X.zarr``."""
    store = Path(path)
    return store.with_name(store.name + '.lock')


def _owner(lock: Path) -> str:
    """Describe who holds ``lock`` from what it says (pid, host, start time)."""
    try:
        info = json.loads(lock.read_text())
        return (f"pid {info['pid']} on {info['host']} since {info['since']}")
    except (OSError, ValueError, KeyError, TypeError):
        return 'another process'


@contextmanager
def store_lock(path: str | Path) -> Iterator[Path]:
    """
    Hold the one-writer lock of the store at ``path`` while the block runs.

    The lock is an exclusive ``flock`` on ``X.zarr.lock`` (beside the store), which holds the
    owner's pid, host and start time. A second writer is refused at once with
    :class:`EnsembleStoreLocked` naming the owner. The kernel releases a ``flock`` when its
    process dies however it dies (SIGKILL included), so the lock file a dead run leaves behind
    is stale by construction: the next run takes it over. The file is removed on release.
    """
    lock = lock_path(path)
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, 'O_CLOEXEC', 0), 0o644)
        except OSError as err:
            raise EnsembleStoreError(f'{path}: cannot create the lock file {lock}: '
                                     f'{err.strerror or err}') from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            os.close(fd)
            if err.errno in (errno.EAGAIN, errno.EACCES):
                raise EnsembleStoreLocked(
                    f'{path}: being written by {_owner(lock)} (lock file {lock}); one writer '
                    'per store: wait for it to end, or write to another path') from None
            raise EnsembleStoreError(f'{path}: cannot lock {lock}: {err.strerror or err}') \
                from None
        try:                                  # the file locked must still be the one named
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)                          # removed by its last owner meanwhile: again
    try:
        info = {'pid': os.getpid(), 'host': socket.gethostname(),
                'since': time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())}
        os.ftruncate(fd, 0)
        os.write(fd, (json.dumps(info) + '\n').encode())
        yield lock
    finally:
        try:
            os.unlink(lock)
        except OSError:
            pass
        os.close(fd)


def _left_out(path: str | Path, attrs: Mapping[str, Any]) -> dict[str, str]:
    """Return the variables a store's run left out, each with how (``attrs[LEFT_OUT_ATTR]``)."""
    left_out = attrs.get(LEFT_OUT_ATTR, {})
    if not isinstance(left_out, Mapping) or not all(
            name in OPTIONAL_VARIABLES and isinstance(how, str) for name, how in left_out.items()):
        raise EnsembleStoreError(f'{path}: damaged ensemble store: attribute {LEFT_OUT_ATTR!r} '
                                 f'is {left_out!r}, not a map of some of {OPTIONAL_VARIABLES} '
                                 'to texts')
    return dict(left_out)


def _left_out_error(path: str | Path, name: str, how: str) -> EnsembleStoreError:
    """Return the error of reading variable ``name``, which the store's run left out."""
    return EnsembleStoreError(f'{path}: no {name!r} in this ensemble store: {how}')


def _check_layout(path: Path, attrs: Mapping[str, Any], names: Collection[str]) -> None:
    """Refuse a store that is not a tumble_ros ensemble of this format, or lacks a variable."""
    if attrs.get('format') != FORMAT:
        raise EnsembleStoreError(f'{path}: not a tumble_ros ensemble store')
    version = attrs.get('format_version')
    if version != FORMAT_VERSION:
        raise EnsembleStoreError(f'{path}: ensemble store format version {version!r}; this '
                                 f'tumble_ros reads and resumes version {FORMAT_VERSION} only')
    left_out = _left_out(path, attrs)
    missing = [name for name in (*VARIABLES, 'chunk_done')
               if name not in names and name not in left_out]
    if missing:
        raise EnsembleStoreError(f'{path}: damaged ensemble store: no variable '
                                 f"{', '.join(missing)}")
    for key in ('n_bodies', 'chunk_size', SCENARIO_ATTR):
        if key not in attrs:
            raise EnsembleStoreError(f'{path}: damaged ensemble store: no attribute {key!r}')


def _fit_reasons(reasons: Iterable[object]) -> npt.NDArray[np.str_]:
    out = []
    for text in reasons:
        text = str(text)
        out.append(text if len(text) <= REASON_WIDTH else text[:REASON_WIDTH - 3] + '...')
    return np.array(out, dtype=f'<U{REASON_WIDTH}')


class EnsembleStore:
    """
    An ensemble store being written: create or resume it, write chunks, see which are done.

    Create with :meth:`create` (a new run) or :meth:`resume` (the same run again: its
    ``attrs['fingerprint']`` must match). Read results with :func:`open_ensemble`.
    ``variables``: the VARIABLES it holds; ``left_out``: those its run left out, each with how.
    """

    def __init__(self, path: str | Path) -> None:
        import zarr

        self.path = Path(path)
        try:
            self._group = zarr.open_group(str(self.path), mode='r+', zarr_format=2)
        except Exception as err:  # zarr raises several types for a missing or foreign store
            raise EnsembleStoreError(f'{self.path}: not an ensemble store '
                                     f"({' '.join(str(err).split())})") from None
        self.attrs: dict[str, Any] = dict(self._group.attrs)
        _check_layout(self.path, self.attrs, set(self._group.array_keys()))
        self.left_out = _left_out(self.path, self.attrs)
        self.variables = tuple(name for name in VARIABLES if name not in self.left_out)
        try:
            self.n_bodies = int(self.attrs['n_bodies'])
            self.chunk_size = int(self.attrs['chunk_size'])
            self.n_chunks = -(-self.n_bodies // self.chunk_size)
            shapes = {name: self._array(name).shape for name in (*self.variables, 'chunk_done')}
        except (TypeError, ValueError, ZeroDivisionError, KeyError) as err:
            raise EnsembleStoreError(f'{self.path}: damaged ensemble store ({err})') from None
        wrong = [name for name, shape in shapes.items()
                 if shape[:1] != ((self.n_chunks,) if name == 'chunk_done' else (self.n_bodies,))]
        if wrong:
            raise EnsembleStoreError(f"{self.path}: damaged ensemble store: {', '.join(wrong)} "
                                     f'not of {self.n_bodies} bodies in {self.n_chunks} chunks')

    def _array(self, name: str) -> Any:
        """Return the Zarr array ``name`` (the layout check found it among the arrays)."""
        return self._group[name]

    @classmethod
    def create(cls, path: str | Path, *, n_bodies: int, times: npt.ArrayLike,
               chunk_size: int, attrs: Mapping[str, Any], overwrite: bool = False,
               left_out: Mapping[str, str] | None = None) -> 'EnsembleStore':
        """
        Create the store at ``path`` for N bodies sampled at ``times`` [yr]; nothing written.

        ``attrs`` (JSON-serialisable: strings, numbers, lists) become the Dataset's attributes.
        An existing path is refused unless ``overwrite`` (then it is removed first).
        ``left_out``: variables of :data:`OPTIONAL_VARIABLES` the run does not write, each
        with how it left them out (the text of the error that reading them raises).
        """
        import dask.array as da
        import xarray as xr

        path = Path(path)
        t = np.asarray(times, dtype=float)
        if n_bodies < 1 or chunk_size < 1 or t.ndim != 1 or t.size < 1:
            raise EnsembleStoreError(f'{path}: needs n_bodies >= 1, chunk_size >= 1 and '
                                     f'sample times, got {n_bodies}, {chunk_size}, '
                                     f'{t.shape}')
        left_out = dict(left_out or {})
        wrong = sorted(set(left_out) - set(OPTIONAL_VARIABLES))
        if wrong:
            raise EnsembleStoreError(f'{path}: left_out: {wrong} cannot be left out; a run '
                                     f'may leave out {list(OPTIONAL_VARIABLES)} only')
        if path.exists() or path.is_symlink():
            if not overwrite:
                raise EnsembleStoreError(f'{path}: exists (resume the same run, or overwrite)')
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
        sizes = {'body': n_bodies, 'time': t.size, 'component': 3, 'angle': 3,
                 'quaternion_component': 4}
        data: dict[str, Any] = {}
        kept = {name: spec for name, spec in VARIABLES.items() if name not in left_out}
        for name, (dims, dtype, var_attrs) in kept.items():
            shape = tuple(sizes[d] for d in dims)
            chunks = (chunk_size,) + shape[1:]
            data[name] = (dims, da.zeros(shape, dtype=dtype, chunks=chunks), var_attrs)
        n_chunks = -(-n_bodies // chunk_size)
        data['chunk_done'] = (('chunk',), np.zeros(n_chunks, dtype=bool),
                              {'long_name': 'chunk of bodies written completely',
                               'bodies': 'chunk i holds bodies [i * chunk_size, '
                                         '(i + 1) * chunk_size)'})
        coords = {'body': np.arange(n_bodies, dtype=np.int64),
                  'time': ('time', t, {'long_name': 'simulated time', 'units': 'yr'}),
                  'component': ['x', 'y', 'z'], 'angle': ['phi', 'psi', 'theta'],
                  'quaternion_component': ['w', 'x', 'y', 'z']}
        all_attrs = {**attrs, 'format': FORMAT, 'format_version': FORMAT_VERSION,
                     'n_bodies': int(n_bodies), 'chunk_size': int(chunk_size)}
        if left_out:
            all_attrs[LEFT_OUT_ATTR] = left_out
        ds = xr.Dataset(data, coords=coords, attrs=all_attrs)
        encoding: dict[str, dict[str, Any]] = {'chunk_done': {'chunks': (1,)}}
        for name, (dims, dtype, _) in kept.items():
            if dtype.startswith('f'):
                encoding[name] = {'_FillValue': np.nan}
        try:
            ds.to_zarr(str(path), mode='w-', compute=False, zarr_format=2, encoding=encoding,
                       consolidated=True)
        except OSError as err:
            raise EnsembleStoreError(f'{path}: cannot create the store: {err}') from None
        return cls(path)

    @classmethod
    def resume(cls, path: str | Path, *, fingerprint: str) -> 'EnsembleStore':
        """Open an existing store to go on writing the same run (same ``fingerprint``)."""
        store = cls(path)
        if store.attrs.get('fingerprint') != fingerprint:
            raise EnsembleStoreError(
                f'{store.path}: holds another run (its scenario, inputs, bodies, sample times, '
                f'chunk size or variables left out differ from this one); write to a new path, '
                f'or overwrite it')
        return store

    def done(self) -> npt.NDArray[np.bool_]:
        """Return (n_chunks,) bool: which chunks are written completely."""
        try:
            return np.asarray(self._array('chunk_done')[:], dtype=bool)
        except (RuntimeError, ValueError, OSError) as err:   # a chunk that does not decode
            raise EnsembleStoreError(f'{self.path}: damaged ensemble store: cannot read '
                                     f"chunk_done ({' '.join(str(err).split())})") from None

    def read(self, name: str, bodies: int | slice = slice(None)) -> npt.NDArray[Any]:
        """Return the stored values of variable ``name`` for ``bodies`` (an index or slice)."""
        if name in self.left_out:
            raise _left_out_error(self.path, name, self.left_out[name])
        return np.asarray(self._array(name)[bodies])

    def write_chunk(self, index: int, start: int, arrays: Mapping[str, Any]) -> None:
        """
        Write chunk ``index`` (bodies ``start`` ...) from ``arrays``.

        ``arrays`` holds every name of ``variables`` (others are not written). The data first,
        then the chunk's ``chunk_done`` flag: a chunk is marked only once all of it is on disk.
        """
        if not 0 <= index < self.n_chunks or start != index * self.chunk_size:
            raise EnsembleStoreError(f'{self.path}: chunk {index} starts at body '
                                     f'{index * self.chunk_size}, not {start}')
        missing = sorted(set(self.variables) - set(arrays))
        if missing:
            raise EnsembleStoreError(f'{self.path}: chunk {index} lacks {missing}')
        stop = min(self.n_bodies, start + self.chunk_size)
        for name in self.variables:
            dtype = VARIABLES[name][1]
            values: npt.NDArray[Any] = _fit_reasons(arrays[name]) if name == 'reason' \
                else np.asarray(arrays[name], dtype=dtype)
            if values.shape[0] != stop - start:
                raise EnsembleStoreError(f'{self.path}: chunk {index}: {name} has '
                                         f'{values.shape[0]} bodies, expected {stop - start}')
            self._array(name)[start:stop] = values
        self._array('chunk_done')[index] = True


def open_ensemble(path: str | Path) -> xarray.Dataset:
    """
    Open an ensemble store as an xarray Dataset (lazy: read as needed, chunk by chunk).

    Everything needed to analyse the run is in it: the samples with their units, the status
    and failure reason of every body, its initial state and number of impacts, and the
    scenario and inputs as attributes (``ds.attrs[SCENARIO_ATTR]``: a ROS 2 parameters file).
    """
    import xarray as xr

    store = Path(path)
    if not store.is_dir():
        raise EnsembleStoreError(f'{store}: no ensemble store there')
    try:
        ds: xarray.Dataset = xr.open_zarr(str(store), consolidated=True)
    except Exception as err:  # zarr/xarray raise several types for a damaged store
        raise EnsembleStoreError(f'{store}: cannot open the ensemble store '
                                 f"({' '.join(str(err).split())})") from None
    _check_layout(store, {str(k): v for k, v in ds.attrs.items()},
                  {str(name) for name in ds.variables})
    return ds


def ensemble_variable(ds: xarray.Dataset, name: str) -> xarray.DataArray:
    """
    Return variable ``name`` of a store opened with :func:`open_ensemble`.

    What analyses of a store read its variables through: a variable the run left out (see
    :data:`OPTIONAL_VARIABLES`) raises an :class:`EnsembleStoreError` naming it and saying how
    the run left it out, where ``ds[name]`` would raise a bare KeyError.
    """
    if name in ds.variables:
        return ds[name]
    where = ds.encoding.get('source', 'ensemble store')
    how = _left_out(where, {str(k): v for k, v in ds.attrs.items()}).get(name)
    if how is None:
        raise EnsembleStoreError(f'{where}: no variable {name!r} in this ensemble store')
    raise _left_out_error(where, name, how)
