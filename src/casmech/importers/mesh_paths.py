"""Where an imported model's mesh files are, and how the written YAML names them.

A URDF names meshes `package://PKG/path`, `file:///abs/path` or relative to the URDF; an MJCF
relative to its `meshdir`. The file is looked for, first found wins:

- `package://PKG/rest`: in each `--mesh-dir DIR` (DIR/PKG/rest, then DIR/rest), in the ROS
  environment (`$ROS_PACKAGE_PATH` entries E: E/PKG/rest; `$AMENT_PREFIX_PATH` and
  `$CMAKE_PREFIX_PATH` entries: E/share/PKG/rest), then in the source file's folders upwards
  (a folder named PKG: it/rest; a folder holding PKG or share/PKG: it/PKG/rest, it/share/PKG/rest);
- `file:///abs/path`: there, then its file name in each `--mesh-dir`;
- a relative name: beside the source, then in each `--mesh-dir`.

A found file is written relative to the folder of the YAML when it is there or below, else as
an absolute path, whose folder `casmech check`/`animate` then need allowed (`--allow-dir DIR`:
`folders_outside` lists them). A file not found keeps its name as the source gives it (relative
to the source's folder, a `package://` prefix dropped): copy the meshes there beside the YAML.
The caller warns.
"""

from __future__ import annotations

import os
from dataclasses import field
from pathlib import Path

from casmech.core.records import record

ROS_PACKAGE_PATHS = "ROS_PACKAGE_PATH"
PREFIX_PATHS = ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH")


def _entries(variable: str) -> list[Path]:
    return [Path(p) for p in os.environ.get(variable, "").split(os.pathsep) if p.strip()]


@record(frozen=False)
class MeshPaths:
    source: Path  # the file being imported
    output_dir: Path  # the folder the YAML is written to
    mesh_dirs: tuple[Path, ...] = ()
    folders_outside: list[Path] = field(default_factory=list)  # of meshes outside output_dir

    def _package(self, package: str, rest: str) -> list[Path]:
        candidates = []
        for folder in self.mesh_dirs:
            candidates += [folder / package / rest, folder / rest]
        candidates += [entry / package / rest for entry in _entries(ROS_PACKAGE_PATHS)]
        for variable in PREFIX_PATHS:
            candidates += [entry / "share" / package / rest for entry in _entries(variable)]
        for folder in self.source.resolve().parents:
            if folder.name == package:
                candidates.append(folder / rest)
            candidates += [folder / package / rest, folder / "share" / package / rest]
        return candidates

    def candidates(self, name: str, base: Path | None = None) -> list[Path]:
        """Where `name` (as the source writes it) may be; `base`: the folder relative names
        start from (default: the source's)."""
        if name.startswith("package://"):
            package, _, rest = name[len("package://"):].partition("/")
            return self._package(package, rest) if rest else []
        if name.startswith("file://"):
            absolute = Path(name[len("file://"):])
            return [absolute] + [folder / absolute.name for folder in self.mesh_dirs]
        base = base if base is not None else self.source.parent
        return [base / name] + [folder / name for folder in self.mesh_dirs]

    def written(self, name: str, base: Path | None = None) -> tuple[str, bool]:
        """(the name to write in the YAML, whether the file was found)."""
        found = next((path for path in self.candidates(name, base) if path.is_file()), None)
        if found is None:
            if name.startswith("package://"):
                return name[len("package://"):].partition("/")[2] or name, False
            if name.startswith("file://"):
                return name[len("file://"):], False
            relative = (base if base is not None else self.source.parent) / name
            return Path(os.path.relpath(relative, self.source.parent)).as_posix(), False
        found = found.resolve()
        output = self.output_dir.resolve()
        if found == output or output in found.parents:
            return found.relative_to(output).as_posix(), True
        if found.parent not in self.folders_outside:
            self.folders_outside.append(found.parent)
        return str(found), True

    def common_outside(self) -> Path | None:
        """The deepest folder holding every mesh outside the output folder (for --allow-dir)."""
        if not self.folders_outside:
            return None
        return Path(os.path.commonpath([str(f) for f in self.folders_outside]))
