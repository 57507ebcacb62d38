"""What a mesh job is doing, in words: the worker's progress lines turned into a status for the user.

The gmsh child writes terse lines for the parent's watchdog (``face 7 0``, ``batch 3 4 5``, ``result 7 0
ok``, ``refine 2 9``; see :mod:`cadedge.mesh.worker`), and the parent adds ``restart EVENT`` when it
carries on in a new child (see :mod:`cadedge.mesh.isolate`; EVENT says what went wrong and what is done
about it, and is shown as it is). :class:`MeshStatus` keeps the count of faces meshed across restarts and
hands ``show`` one line per step, e.g. ``meshing faces: 12/40 meshed, face 13``. A face the child names
beyond those it was given (a repeated face meshed on its own after all: :mod:`cadedge.mesh.instances`)
joins the count, so the count never passes its total. Lines it does not know are left out.

>>> lines = []
>>> status = MeshStatus(lines.append, faces=[1, 2, 3])
>>> for line in ("import", "curves", "batch 1 2", "result 1 0 ok", "result 2 0 ok", "face 3 0",
...              "result 3 0 fail gmsh error", "face 3 1", "result 3 1 ok", "measure", "refine 2",
...              "optimise 3", "read", "face 4 0", "result 4 0 ok"):
...     status(line)
>>> print("\\n".join(lines))
gmsh: importing the model
gmsh: meshing the curves
meshing faces: 0/3 meshed, faces 1 2 together
meshing faces: 1/3 meshed, faces 1 2 together
meshing faces: 2/3 meshed, faces 1 2 together
meshing faces: 2/3 meshed, face 3
meshing faces: 2/3 meshed, face 3 (attempt 2)
meshing faces: 3/3 meshed
area target: measuring the faces
meshing face 2 again
improving the triangles: face 3
reading the mesh back
meshing faces: 3/4 meshed, face 4
meshing faces: 4/4 meshed
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

#: Steps of the worker that are shown as they are.
STEPS = {"import": "gmsh: importing the model", "map": "gmsh: matching its entities to the B-rep",
         "sizes": "gmsh: setting sizes", "curves": "gmsh: meshing the curves",
         "measure": "area target: measuring the faces", "read": "reading the mesh back",
         "write": "writing the mesh", "place": "placing the meshes of repeated faces"}
#: Faces named in one status line, at most; the rest are counted.
MAX_NAMED = 6


class MeshStatus:
    """A ``progress(line)`` callback for :func:`~cadedge.mesh.isolate.run_isolated` that calls ``show(text)``
    with what the job is doing and how many of its ``faces`` (ids) are meshed."""

    def __init__(self, show: Callable[[str], None], *, faces: Iterable[int]):
        self.show, self.faces = show, set(faces)
        self.meshed: set[int] = set()
        self.doing = ""

    def __call__(self, line: str) -> None:
        words = line.split()
        if not words:
            return
        head, args = words[0], words[1:]
        if head in STEPS:
            self.show(STEPS[head])
        elif head == "face" and len(args) == 2:
            self.faces.add(int(args[0]))
            attempt = int(args[1])
            self.doing = f"face {args[0]}" + (f" (attempt {attempt + 1})" if attempt else "")
            self._faces()
        elif head == "batch" and args:
            self.faces.update(map(int, args))
            self.doing = f"faces {_named(args)} together" if len(args) > 1 else f"face {args[0]}"
            self._faces()
        elif head == "result" and len(args) >= 3 and args[2] == "ok":
            self.meshed.add(int(args[0]))
            self.faces.add(int(args[0]))
            self._faces()
        elif head == "refine" and args:
            self.show(f"meshing face{'s' if len(args) > 1 else ''} {_named(args)} again")
        elif head == "optimise" and args:
            self.show(f"improving the triangles: face {args[0]}")
        elif head == "restart" and args:
            self.show(line.split(None, 1)[1])  # what the watchdog saw and did, in its own words

    def _faces(self) -> None:
        done, total = len(self.meshed), len(self.faces)
        self.show(f"meshing faces: {done}/{total} meshed" + (f", {self.doing}" if done < total else ""))


def _named(ids: list[str]) -> str:
    if len(ids) <= MAX_NAMED:
        return " ".join(ids)
    return " ".join(ids[:MAX_NAMED]) + f" and {len(ids) - MAX_NAMED} more"
