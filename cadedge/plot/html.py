"""Interactive HTML pages drawn with plotly: one self-contained file that turns in 3-D and works offline.

plotly.js is inlined (``include_plotlyjs=True``, about 4.7 MB), so the page needs no network at view
time. The edges form a line trace (grid points as small dots) coloured by the number of segments
or the estimated ALD of their edge, with buttons to switch; hovering an edge shows its id, curve
type, segments, length and ALD. B-rep vertices are a marker trace; a mesh's triangles are
one ``Mesh3d`` trace coloured by B-rep face, hovering shows the face id. The legend hides or shows
each trace.
"""

from __future__ import annotations

import html
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from ..atomic import atomic_path
from ..shapegrid import ShapeGrid

if TYPE_CHECKING:
    from ..mesh import MeshResult

COLORSCALE = "Viridis"
EDGE_TRACE = "edges"
CONFIG = {"displaylogo": False, "responsive": True, "scrollZoom": True}


def _edge_columns(grid: ShapeGrid) -> dict[str, np.ndarray]:
    """All non-degenerate polylines in one array, a NaN row after each edge (a gap in the line), with
    per-point copies of their edge's id, curve, segments, length and ALD (rounded to what the hover
    label shows, which keeps the page small)."""
    live = [e for e in grid.edges if not e.degenerate]
    if not live:
        return {"xyz": np.zeros((0, 3)), "custom": np.zeros((0, 5), dtype=object),
                "segments": np.zeros(0), "ald": np.zeros(0)}
    counts = np.array([len(e.points) + 1 for e in live])
    xyz = np.concatenate([np.vstack([np.asarray(e.points, dtype=float), np.full((1, 3), np.nan)]) for e in live])
    per_edge = {"id": [e.id for e in live], "curve": [e.curve for e in live],
                "segments": [e.segments for e in live], "length": [float(f"{e.length:.7g}") for e in live],
                "ald": [float(f"{e.ald_estimate:.4g}") for e in live]}
    custom = np.empty((len(xyz), 5), dtype=object)
    for k, key in enumerate(("id", "curve", "segments", "length", "ald")):
        custom[:, k] = np.repeat(np.array(per_edge[key], dtype=object), counts)
    return {"xyz": xyz, "custom": custom, "segments": np.repeat(np.array(per_edge["segments"], float), counts),
            "ald": np.repeat(np.array(per_edge["ald"]), counts)}


def _edge_traces(grid: ShapeGrid, cols: dict[str, np.ndarray], color_by: str) -> list[Any]:
    """The polylines (a line trace with the hover labels), their grid points (a marker trace carrying
    the colour bar and the legend entry of both: plotly.js cannot draw a legend swatch for a line
    coloured by an array) and the B-rep vertices."""
    import plotly.graph_objects as go

    x, y, z = cols["xyz"].T
    values = cols[color_by]
    hover = ("edge %{customdata[0]} (%{customdata[1]})<br>segments %{customdata[2]}<br>"
             f"length %{{customdata[3]:.6~g}} {html.escape(grid.units)}<br>ALD %{{customdata[4]:.3~g}}<extra></extra>")
    lines = go.Scatter3d(x=x, y=y, z=z, mode="lines", showlegend=False, name=EDGE_TRACE, legendgroup=EDGE_TRACE,
                         customdata=cols["custom"], hovertemplate=hover,
                         line=dict(color=values, colorscale=COLORSCALE, width=5))
    points = go.Scatter3d(x=x, y=y, z=z, mode="markers", name=EDGE_TRACE, legendgroup=EDGE_TRACE, hoverinfo="skip",
                          marker=dict(size=2, color=values, colorscale=COLORSCALE, showscale=True,
                                      colorbar=dict(title=dict(text=_label(color_by)))))
    vpoints = np.array([np.reshape(v.point, 3) for v in grid.vertices], dtype=float).reshape(-1, 3)
    vertices = go.Scatter3d(
        x=vpoints[:, 0], y=vpoints[:, 1], z=vpoints[:, 2], mode="markers", name="vertices",
        customdata=np.array([v.id for v in grid.vertices]), hovertemplate="vertex %{customdata}<extra></extra>",
        marker=dict(size=3, color="black", symbol="circle-open"))
    return [lines, points, vertices]


def _label(color_by: str) -> str:
    return "segments" if color_by == "segments" else "ALD"


def _color_buttons(cols: dict[str, np.ndarray], first: int) -> list[dict[str, Any]]:
    """Buttons that recolour the edge traces (``first`` and ``first + 1``) by segments or by ALD."""
    buttons = []
    for key in ("segments", "ald"):
        values = cols[key].tolist()
        buttons.append(dict(label=f"colour by {_label(key)}", method="restyle",
                            args=[{"line.color": [values, values], "marker.color": [values, values],
                                   "marker.colorbar.title.text": _label(key)}, [first, first + 1]]))
    return [dict(type="buttons", direction="right", x=0.0, xanchor="left", y=1.0, yanchor="top",
                 buttons=buttons, showactive=True)]


def _layout(fig: Any, grid: ShapeGrid, cols: dict[str, np.ndarray], title: str, first_edge_trace: int,
            color_by: str) -> None:
    unit = f" [{grid.units}]"
    menus = _color_buttons(cols, first_edge_trace)
    menus[0]["active"] = 0 if color_by == "segments" else 1
    fig.update_layout(
        title=dict(text=html.escape(title), x=0.5, font=dict(size=14)), updatemenus=menus,
        scene=dict(aspectmode="data", xaxis_title="x" + unit, yaxis_title="y" + unit, zaxis_title="z" + unit),
        legend=dict(x=0.0, y=0.92), margin=dict(l=0, r=0, t=40, b=0), hoverlabel=dict(align="left"))


def _write(fig: Any, path: str | os.PathLike) -> None:
    """One standalone page: plotly.js inline, the figure filling the window, its title (already
    HTML-escaped for plotly) as the page title."""
    div = fig.to_html(full_html=False, include_plotlyjs=True, config=CONFIG, default_width="100%",
                      default_height="100vh")
    page = ("<!DOCTYPE html>\n<html>\n<head>\n<meta charset=\"utf-8\">\n"
            f"<title>{fig.layout.title.text}</title>\n"
            "<style>html, body { margin: 0; height: 100%; overflow: hidden; }</style>\n"
            f"</head>\n<body>\n{div}\n</body>\n</html>\n")
    with atomic_path(path) as tmp:
        tmp.write_text(page, encoding="utf-8")


def grid_figure(grid: ShapeGrid, *, color_by: str = "segments", title: str | None = None) -> Any:
    """The plotly ``Figure`` of the edge grids of ``grid`` (e.g. to show in a notebook)."""
    import plotly.graph_objects as go

    title = title or (f"{grid.source}: {len(grid.edges)} edges, {grid.segments} segments, "
                      f"ALD <= {grid.max_ald_estimate:.2g}")
    cols = _edge_columns(grid)
    fig = go.Figure(_edge_traces(grid, cols, color_by))
    _layout(fig, grid, cols, title, 0, color_by)
    return fig


def grid_html(grid: ShapeGrid, path: str | os.PathLike, *, color_by: str = "segments",
              title: str | None = None) -> None:
    """Write an interactive page of the edge grids of ``grid`` to ``path``."""
    fig = grid_figure(grid, color_by=color_by, title=title)
    _write(fig, path)


def _palette() -> list[str]:
    from plotly.colors import qualitative

    return list(qualitative.Pastel + qualitative.Set3)


def _stepped_colorscale(colours: list[str]) -> list[list[Any]]:
    """Intensity k (on [-0.5, len - 0.5]) gets ``colours[k]``, unblended."""
    n = len(colours)
    return [stop for k, c in enumerate(colours) for stop in ([k / n, c], [(k + 1) / n, c])]


def _split_by_face(nodes: np.ndarray, triangles: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, ...]:
    """Nodes repeated once per face that uses them, so every node belongs to one face: plotly's mesh
    hover reports a node, and its ``customdata`` is then that face's id. Returns the new nodes, the
    triangles on them and each new node's face id."""
    n = max(len(nodes), 1)
    keys = np.repeat(faces, 3) * n + triangles.ravel()
    unique, inverse = np.unique(keys, return_inverse=True)
    return nodes[unique % n], inverse.reshape(-1, 3), unique // n


def mesh_figure(result: MeshResult, *, color_by: str = "segments", title: str | None = None) -> Any:
    """The plotly ``Figure`` of the triangles of ``result`` (coloured by B-rep face) and its edge grids.

    Faces take the colours of a small palette in turn (plotly.js shades a mesh with at most 256
    colours, so there cannot be one per face on a large model); hovering shows the face id.
    """
    import plotly.graph_objects as go

    grid = result.grid
    triangles = np.asarray(result.triangles, dtype=np.int64).reshape(-1, 3)
    faces = np.asarray(result.triangle_faces, dtype=np.int64)
    nodes, corners, node_face = _split_by_face(np.asarray(result.nodes, dtype=float).reshape(-1, 3),
                                               triangles, faces)
    palette = _palette()
    surface = go.Mesh3d(
        x=nodes[:, 0], y=nodes[:, 1], z=nodes[:, 2], i=corners[:, 0], j=corners[:, 1], k=corners[:, 2],
        intensity=((node_face - 1) % len(palette)).astype(float), intensitymode="vertex",
        colorscale=_stepped_colorscale(palette), cmin=-0.5, cmax=len(palette) - 0.5, showscale=False,
        flatshading=True, name="faces", showlegend=True, customdata=node_face,
        hovertemplate="face %{customdata}<extra></extra>",
        lighting=dict(ambient=0.7, diffuse=0.4, specular=0.05, roughness=1.0, fresnel=0.0,
                      facenormalsepsilon=0.0, vertexnormalsepsilon=0.0))  # small triangles keep their light
    title = title or (f"{result.source}: {len(triangles)} triangles on {len(np.unique(faces))} faces, "
                      f"{grid.segments} edge segments")
    cols = _edge_columns(grid)
    fig = go.Figure([surface, *_edge_traces(grid, cols, color_by)])
    _layout(fig, grid, cols, title, 1, color_by)
    return fig


def mesh_html(result: MeshResult, path: str | os.PathLike, *, color_by: str = "segments",
              title: str | None = None) -> None:
    """Write an interactive page of the triangles of ``result`` and its edge grids to ``path``."""
    fig = mesh_figure(result, color_by=color_by, title=title)
    _write(fig, path)
