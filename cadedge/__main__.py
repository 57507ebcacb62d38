"""``python -m cadedge ...``: the same command line as the ``cadedge`` console script."""

from __future__ import annotations

from .cli import entry

if __name__ == "__main__":
    entry()
