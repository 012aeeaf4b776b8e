"""softhap.Series: a time series of a body's shapes as .vtu frames and the .pvd index that
ParaView (and pyvista) open as one animated dataset."""

from __future__ import annotations

import os
import pathlib
from typing import List, Tuple, Union
from xml.sax.saxutils import quoteattr

from .body import Body


class Series:
    """Frames of one or more bodies over time, written as they come.

        with softhap.Series("frames", "liver") as series:
            for i in range(60):
                world.step(1 / 60)
                series.add(body, time=(i + 1) / 60)

    add() writes <folder>/<name>_<frame>.vtu (Body.write_vtu) and rewrites <folder>/<name>.pvd,
    so that the index is complete after every frame (a run stopped half-way still opens).
    """

    def __init__(self, folder: Union[str, os.PathLike], name: str = "frames") -> None:
        """Write into folder (made if missing) under name (the .pvd's and the frames' stem)."""
        self.folder = pathlib.Path(folder)
        self.name = name
        self.folder.mkdir(parents=True, exist_ok=True)
        self._frames: List[Tuple[float, int, str]] = []

    @property
    def index_path(self) -> pathlib.Path:
        """The .pvd file."""
        return self.folder / (self.name + ".pvd")

    @property
    def frame_count(self) -> int:
        """Frames written so far."""
        return len(self._frames)

    def add(self, body: Body, time: float, part: int = 0) -> pathlib.Path:
        """Write body's current shape as the frame at time (s); part tells several bodies of
        the same instant apart (ParaView shows each part as its own block). Returns the .vtu
        path."""
        file = "%s_%04d_%d.vtu" % (self.name, len(self._frames), part)
        body.write_vtu(self.folder / file)
        self._frames.append((float(time), int(part), file))
        self._write_index()
        return self.folder / file

    def _write_index(self) -> None:
        lines = ['<?xml version="1.0"?>',
                 '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">', "  <Collection>"]
        for time, part, file in self._frames:
            lines.append('    <DataSet timestep="%r" part="%d" file=%s/>' % (time, part, quoteattr(file)))
        lines += ["  </Collection>", "</VTKFile>", ""]
        self.index_path.write_text("\n".join(lines))

    def __enter__(self) -> Series:
        """The series itself (every frame is complete as soon as add() returns)."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Nothing to flush: the index is rewritten at every add()."""
        return None
