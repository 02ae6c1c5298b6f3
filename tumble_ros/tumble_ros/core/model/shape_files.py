"""
Shape files: read and write the triangulated surfaces of :class:`~.mass_models.Polyhedron`.

Two text formats, told apart by their content (not their extension):

- **Wavefront OBJ**: ``v x y z`` lines (vertices, numbered from 1 in file order) and
  ``f i j k ...`` lines (facets; an index may be ``i/t/n`` or ``i//n``, only ``i`` is used;
  a negative index counts back from the last vertex read). A polygon of more than three
  vertices is split into a fan of triangles (i, j, k), (i, k, l)... (right for the convex
  planar polygons shape files hold). Every other line (``#`` comments, ``vn``, ``vt``, ``o``,
  ``g``, ``s``, ``usemtl``, ``mtllib``...) is ignored. The PDS radar shape models
  (EAR-A-5-DDR-RADARSHAPE-MODELS, e.g. ``toutatis.lbl``: "the format v x1 y1 z1 ... f i1 j1 k1
  ... vertices are implicitly numbered beginning with 1. The units are kilometers ... This
  format is identical to a Wavefront OBJ file") are read this way.
- **Vertex/facet counts** (the PDS Small Bodies Node plate model tables, e.g. the
  ``COUNTS_TABLE``, ``VERTEX_TABLE`` and ``PLATE_TABLE`` of ``steins_cart.lbl``, and the text
  files radar shape software writes): a first line with the number of vertices n and of
  facets m, then n lines ``x y z``, then m lines ``i j k`` of 1-based vertex indices. A line
  may start with its own 1-based row number (``k x y z`` / ``k i j k``): four columns are read
  that way.

Coordinates are in km. Facets are to run counter-clockwise seen from outside (the outward
normal of the right-hand rule), as every shape model archive states; :class:`Polyhedron`
refuses a surface whose volume comes out negative. An error names the file, the line and the
problem (:class:`ShapeFileError`).

Shipped shapes live in ``config/shapes/`` (installed to ``share/tumble_ros/config/shapes`` by
colcon, into the import package by pip: :mod:`.shipped`);
:func:`resolve_shape_path` finds the file a params file names.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

from tumble_ros.core.array_types import ArrayLike, FloatArray
from tumble_ros.core.model.limits import MAX_FACETS, MAX_SHAPE_FILE_BYTES, ScenarioError
from tumble_ros.core.model.mass_models import MassModelError, Polyhedron
from tumble_ros.core.model.shipped import package_dir
from tumble_ros.core.model.user_files import read_user_text

__all__ = ['ShapeFileError', 'Mesh', 'read_mesh', 'load_shape', 'write_obj', 'write_counts',
           'resolve_shape_path', 'SHAPES_DIR', 'box_mesh', 'ellipsoid_mesh']

#: Where the shipped shapes are in the source tree (and, installed, under share/tumble_ros).
SHAPES_DIR = Path('config') / 'shapes'


class ShapeFileError(ScenarioError):
    """A shape file that cannot be read: the message names the file, the line, the problem."""


class Mesh:
    """Vertices (n, 3) [km], facets (m, 3) 0-based, each facet's and vertex's line in its file."""

    def __init__(self, vertices: FloatArray, facets: np.ndarray, lines: np.ndarray,
                 vertex_lines: np.ndarray) -> None:
        self.vertices = vertices
        self.facets = facets
        self.lines = lines
        self.vertex_lines = vertex_lines


def _too_many(path: Path, line: int | None, what: str, count: str) -> ShapeFileError:
    return _error(path, line, f'more than {MAX_FACETS:,} {what} (MAX_FACETS: twice the largest '
                  f'radar shape model; decimate the mesh), {count}')


def _error(path: Path, line: int | None, why: str) -> ShapeFileError:
    where = f'{path}, line {line}' if line is not None else f'{path}'
    return ShapeFileError(f'shape_file: {where}: {why}')


def _numbers(path: Path, line: int, tokens: Sequence[str], kind: type, what: str) -> list[float]:
    try:
        return [kind(t) for t in tokens]
    except ValueError:
        raise _error(path, line, f'{what}: {" ".join(tokens)!r} are not '
                     f'{"integers" if kind is int else "numbers"}') from None


def _read_obj(path: Path, rows: list[tuple[int, list[str]]]) -> Mesh:
    vertices: list[list[float]] = []
    facets: list[tuple[int, int, int]] = []
    lines: list[int] = []
    vertex_lines: list[int] = []
    for number, tokens in rows:
        key = tokens[0]
        if key == 'v':
            if len(tokens) < 4:
                raise _error(path, number, f'a vertex needs x y z, got {" ".join(tokens)!r}')
            if len(vertices) >= MAX_FACETS:
                raise _too_many(path, number, 'vertices', f'{len(vertices) + 1:,} so far')
            vertices.append(_numbers(path, number, tokens[1:4], float, 'vertex'))
            vertex_lines.append(number)
        elif key == 'f':
            if len(tokens) < 4:
                raise _error(path, number, f'a facet needs 3 vertices, got {" ".join(tokens)!r}')
            refs = _numbers(path, number, [t.split('/')[0] for t in tokens[1:]], int, 'facet')
            index = []
            for r in refs:
                k = int(r) - 1 if r > 0 else len(vertices) + int(r)
                if r == 0 or not 0 <= k < len(vertices):
                    raise _error(path, number, f'facet vertex {int(r)} does not exist '
                                 f'({len(vertices)} vertices read so far)')
                index.append(k)
            for j in range(1, len(index) - 1):
                facets.append((index[0], index[j], index[j + 1]))
                lines.append(number)
            if len(facets) > MAX_FACETS:
                raise _too_many(path, number, 'facets', f'{len(facets):,} so far')
    return Mesh(np.array(vertices, dtype=float).reshape(-1, 3),
                np.array(facets, dtype=np.int64).reshape(-1, 3), np.array(lines),
                np.array(vertex_lines))


def _read_counts(path: Path, rows: list[tuple[int, list[str]]]) -> Mesh:
    number, head = rows[0]
    n_v, n_f = (int(x) for x in _numbers(path, number, head[:2], int, 'counts'))
    for what, count in (('facets', n_f), ('vertices', n_v)):
        if count > MAX_FACETS:
            raise _too_many(path, number, what, f'{count:,} announced')
    if len(rows) - 1 < n_v + n_f:
        raise _error(path, None, f'the first line announces {n_v} vertices and {n_f} facets, '
                     f'the file holds {len(rows) - 1} data lines')
    vertices = np.empty((n_v, 3))
    for k, (number, tokens) in enumerate(rows[1:1 + n_v]):
        if len(tokens) not in (3, 4):
            raise _error(path, number, f'vertex {k + 1}: expected x y z, got {" ".join(tokens)!r}')
        vertices[k] = _numbers(path, number, tokens[-3:], float, 'vertex')
    facets = np.empty((n_f, 3), dtype=np.int64)
    lines = np.empty(n_f, dtype=np.int64)
    for k, (number, tokens) in enumerate(rows[1 + n_v:1 + n_v + n_f]):
        if len(tokens) not in (3, 4):
            raise _error(path, number, f'facet {k + 1}: expected i j k, got {" ".join(tokens)!r}')
        refs = _numbers(path, number, tokens[-3:], int, 'facet')
        for r in refs:
            if not 1 <= r <= n_v:
                raise _error(path, number, f'facet {k + 1}: vertex {int(r)} does not exist '
                             f'(vertices are numbered 1 to {n_v})')
        facets[k] = [int(r) - 1 for r in refs]
        lines[k] = number
    if len(rows) > 1 + n_v + n_f:
        number, tokens = rows[1 + n_v + n_f]
        raise _error(path, number, f'data after the {n_v} vertices and {n_f} facets the first '
                     f'line announces: {" ".join(tokens)!r}')
    return Mesh(vertices, facets, lines, np.array([k for k, _ in rows[1:1 + n_v]]))


def _count_obj_lines(path: Path, text: str) -> None:
    """
    Refuse an OBJ text of more than MAX_FACETS facet or vertex lines before parsing it.

    Counted in C (``str.count``, ~0.02 s for 40 MB): parsing the lines in Python takes seconds
    per 10^5 (a 10^6-facet file took 300 s). A lower bound (a polygon is several triangles, an
    indented line is not counted): the readers count exactly as they go.
    """
    for what, key in (('facets', 'f'), ('vertices', 'v')):
        count = text.count(f'\n{key} ') + text.count(f'\n{key}\t') + text.startswith(f'{key} ')
        if count > MAX_FACETS:
            raise _too_many(path, None, what, f'{count:,} {key!r} lines')


def read_mesh(path: str | Path) -> Mesh:
    """
    Read the vertices and facets of a shape file (either format, told by its content).

    Raises :class:`ShapeFileError` naming the file, the line and the problem; a path that is
    no regular file (a FIFO, a device, a directory), a file above
    :data:`~.limits.MAX_SHAPE_FILE_BYTES` or not UTF-8 text (:mod:`.user_files`),
    and more than :data:`~.limits.MAX_FACETS` facets or vertices are refused before the work.
    """
    path = Path(path)
    text = read_user_text(path, f'shape_file: {path}', MAX_SHAPE_FILE_BYTES,
                          'MAX_SHAPE_FILE_BYTES', 'shape file', ShapeFileError)
    _count_obj_lines(path, text)
    rows = [(k + 1, line.split()) for k, line in enumerate(text.splitlines())]
    rows = [(k, t) for k, t in rows if t and not t[0].startswith('#')]
    if not rows:
        raise _error(path, None, 'holds no vertices and no facets')
    first = rows[0][1]
    if len(first) == 2 and all(t.lstrip('+').isdigit() for t in first):
        mesh = _read_counts(path, rows)
    else:
        mesh = _read_obj(path, rows)
    if len(mesh.vertices) < 4 or len(mesh.facets) < 4:
        raise _error(path, None, f'{len(mesh.vertices)} vertices and {len(mesh.facets)} facets: '
                     'a closed surface needs at least 4 of each')
    return mesh


def load_shape(path: str | Path, density: float) -> Polyhedron:
    """
    Return the :class:`Polyhedron` of a shape file [km] at ``density`` [kg/m^3], as read.

    In the file's frame (call :meth:`Polyhedron.in_principal_axes` for the body's). A mesh that
    is no closed, outward-oriented surface is refused naming the file and the facet's line.
    """
    mesh = read_mesh(path)
    try:
        return Polyhedron(mesh.vertices, mesh.facets, density)
    except MassModelError as exc:
        line = (int(mesh.lines[exc.facet]) if exc.facet is not None
                else int(mesh.vertex_lines[exc.vertex]) if exc.vertex is not None else None)
        raise _error(Path(path), line, str(exc)) from None


def write_obj(path: str | Path, vertices: ArrayLike, facets: ArrayLike,
              comment: str = '') -> None:
    """Write a Wavefront OBJ file (vertices [km], facets 0-based; written 1-based)."""
    v, f = np.asarray(vertices, dtype=float), np.asarray(facets, dtype=int)
    head = ''.join(f'# {line}\n' for line in comment.splitlines())
    body = ''.join(f'v {x:.12g} {y:.12g} {z:.12g}\n' for x, y, z in v)
    body += ''.join(f'f {i + 1} {j + 1} {k + 1}\n' for i, j, k in f)
    Path(path).write_text(head + body)


def write_counts(path: str | Path, vertices: ArrayLike, facets: ArrayLike) -> None:
    """Write the vertex/facet counts format (first line ``n m``; facets 1-based)."""
    v, f = np.asarray(vertices, dtype=float), np.asarray(facets, dtype=int)
    body = f'{len(v)} {len(f)}\n'
    body += ''.join(f'{x:.12g} {y:.12g} {z:.12g}\n' for x, y, z in v)
    body += ''.join(f'{i + 1} {j + 1} {k + 1}\n' for i, j, k in f)
    Path(path).write_text(body)


def _package_share() -> Path | None:
    """Return share/tumble_ros when the package is installed (ament index), else None."""
    prefixes = os.environ.get('AMENT_PREFIX_PATH', '')
    for prefix in prefixes.split(os.pathsep):
        candidate = Path(prefix) / 'share' / 'tumble_ros'
        if prefix and (candidate / 'package.xml').exists():
            return candidate
    return None


def resolve_shape_path(name: str | Path, params_file: str | Path | None = None) -> Path:
    """
    Return the shape file a params file names: the first of these that exists.

    Of any kind: :func:`read_mesh` refuses what is no regular file, naming its kind.

    1. ``name`` itself when absolute;
    2. relative to the directory of ``params_file`` (when given);
    3. relative to the package's share directory (``share/tumble_ros``, found on
       ``AMENT_PREFIX_PATH``), e.g. ``config/shapes/apophis.obj``;
    4. relative to the package's own files (:func:`~.shipped.package_dir`: the source tree's
       ``tumble_ros/``, or the import package as pip installs it), the same path (for a run
       from a checkout without a colcon install, or from a pip install).

    Raises :class:`ShapeFileError` listing the places tried.
    """
    path = Path(name).expanduser()
    if path.is_absolute():
        if path.exists():        # (a FIFO, a device: refused by kind when read, not as missing)
            return path
        raise ShapeFileError(f'shape_file: {str(name)!r} does not exist')
    tried = []
    bases = []
    if params_file is not None:
        bases.append(Path(params_file).resolve().parent)
    share = _package_share()
    if share is not None:
        bases.append(share)
    bases.append(package_dir())
    for base in bases:
        candidate = base / path
        tried.append(str(candidate))
        if candidate.exists():
            return candidate
    raise ShapeFileError(f'shape_file: {str(name)!r} not found; tried {", ".join(tried)}')


# -- Meshes of simple bodies (tests, shipped shapes) -------------------------------------------


def box_mesh(half_edges: Sequence[float]) -> tuple[FloatArray, np.ndarray]:
    """Return (vertices, facets) of an axis-aligned box of ``half_edges`` [km], outward."""
    a, b, c = half_edges
    v = np.array([[x, y, z] for x in (-a, a) for y in (-b, b) for z in (-c, c)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = np.array([t for q in quads for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))])
    return v, f


def ellipsoid_mesh(semi_axes: Sequence[float],
                   subdivisions: int) -> tuple[FloatArray, np.ndarray]:
    """
    Return (vertices, facets) inscribed in the ellipsoid of ``semi_axes`` [km], outward.

    An icosahedron whose facets are split in four ``subdivisions`` times, its vertices pushed
    onto the unit sphere and scaled by the semi-axes: 20 4^k facets, 10 4^k + 2 vertices.
    """
    t = (1.0 + 5.0 ** 0.5) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    points = [np.array(p, dtype=float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        middle: dict[tuple[int, int], int] = {}

        def mid(i: int, j: int) -> int:
            key = (min(i, j), max(i, j))
            if key not in middle:
                p = points[i] + points[j]
                points.append(p / np.linalg.norm(p))
                middle[key] = len(points) - 1
            return middle[key]
        new = []
        for i, j, k in faces:
            a, b, c = mid(i, j), mid(j, k), mid(k, i)
            new += [(i, a, c), (j, b, a), (k, c, b), (a, b, c)]
        faces = new
    vertices = np.array(points) * np.asarray(semi_axes, dtype=float)
    return vertices, np.array(faces, dtype=np.int64)
