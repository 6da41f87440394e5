"""A minimal PEP 517/660 build backend for manipid_client, standard library only.

Why: pip builds in an isolated environment and installs the backend's requirements there
from the package index; with setuptools as backend, `pip install ./clients/python` fails on
a machine without PyPI access. This backend needs nothing, so the plain command works
offline with any pip ≥ 21.3 (Debian bookworm has 23.0.1).

It builds a pure-Python wheel of manipid_client/ (metadata from pyproject.toml, version from
manipid_client/__init__.py), an editable wheel (a .pth file pointing at this folder, for
`pip install -e`), and an sdist.
"""
from __future__ import annotations

import base64
import hashlib
import io
import os
import re
import tarfile
import time
import zipfile
from pathlib import Path
from typing import Dict, List, Optional, Tuple

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = "manipid_client"
SDIST_FILES = ("pyproject.toml", "README.md", "_build/manipid_build.py")
# Fixed timestamp: the same sources give the same wheel bytes.
ZIP_TIME = (2024, 1, 1, 0, 0, 0)


def _project() -> Dict:
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    try:
        import tomllib  # Python ≥ 3.11
        return tomllib.loads(text)["project"]
    except ImportError:
        # Older Pythons: the [project] table here holds only simple `key = "value"` strings
        # that matter for the metadata.
        section = text.split("[project]", 1)[1].split("\n[", 1)[0]
        return dict(re.findall(r'^(\w[\w-]*)\s*=\s*"([^"]*)"', section, re.M))


def _version() -> str:
    text = (ROOT / PACKAGE / "__init__.py").read_text(encoding="utf-8")
    match = re.search(r'^__version__\s*=\s*"([^"]+)"', text, re.M)
    if not match:
        raise RuntimeError(f"{PACKAGE}/__init__.py has no __version__")
    return match.group(1)


def _names() -> Tuple[str, str, str]:
    project = _project()
    name = project["name"]
    return name, re.sub(r"[-_.]+", "_", name), _version()


def _metadata() -> str:
    project = _project()
    name, _, version = _names()
    lines = [
        "Metadata-Version: 2.1",
        f"Name: {name}",
        f"Version: {version}",
        f"Summary: {project.get('description', '')}",
        f"Requires-Python: {project.get('requires-python', '>=3.9')}",
    ]
    extras = project.get("optional-dependencies", {})
    if isinstance(extras, dict):
        for extra, requirements in extras.items():
            lines.append(f"Provides-Extra: {extra}")
            lines += [f'Requires-Dist: {requirement}; extra == "{extra}"' for requirement in requirements]
    readme = ROOT / "README.md"
    if readme.is_file():
        lines.append("Description-Content-Type: text/markdown")
        return "\n".join(lines) + "\n\n" + readme.read_text(encoding="utf-8")
    return "\n".join(lines) + "\n"


def _package_files() -> List[Path]:
    return sorted(path for path in (ROOT / PACKAGE).rglob("*")
                  if path.is_file() and "__pycache__" not in path.parts and path.suffix not in (".pyc", ".pyo"))


def _record_line(archive_name: str, data: bytes) -> str:
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{archive_name},sha256={digest},{len(data)}"


def _write_wheel(directory: str, files: List[Tuple[str, bytes]]) -> str:
    _, distribution, version = _names()
    dist_info = f"{distribution}-{version}.dist-info"
    files = files + [
        (f"{dist_info}/METADATA", _metadata().encode()),
        (f"{dist_info}/WHEEL", b"Wheel-Version: 1.0\nGenerator: manipid_build\nRoot-Is-Purelib: true\nTag: py3-none-any\n"),
    ]
    record = [_record_line(name, data) for name, data in files] + [f"{dist_info}/RECORD,,"]
    files.append((f"{dist_info}/RECORD", ("\n".join(record) + "\n").encode()))
    filename = f"{distribution}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(os.path.join(directory, filename), "w", zipfile.ZIP_DEFLATED) as wheel:
        for name, data in files:
            info = zipfile.ZipInfo(name, ZIP_TIME)
            info.external_attr = 0o644 << 16
            info.compress_type = zipfile.ZIP_DEFLATED
            wheel.writestr(info, data)
    return filename


# --- PEP 517 hooks -------------------------------------------------------------------------
def get_requires_for_build_wheel(config_settings: Optional[dict] = None) -> List[str]:
    return []


def get_requires_for_build_sdist(config_settings: Optional[dict] = None) -> List[str]:
    return []


def get_requires_for_build_editable(config_settings: Optional[dict] = None) -> List[str]:
    return []


def build_wheel(wheel_directory: str, config_settings: Optional[dict] = None,
                metadata_directory: Optional[str] = None) -> str:
    files = [(path.relative_to(ROOT).as_posix(), path.read_bytes()) for path in _package_files()]
    return _write_wheel(wheel_directory, files)


def build_editable(wheel_directory: str, config_settings: Optional[dict] = None,
                   metadata_directory: Optional[str] = None) -> str:
    # A .pth line puts this folder on sys.path: the package is used in place, so
    # local_server() can also find the repository's build/ folder from its own file.
    return _write_wheel(wheel_directory, [(f"{PACKAGE}.pth", (str(ROOT) + "\n").encode())])


def build_sdist(sdist_directory: str, config_settings: Optional[dict] = None) -> str:
    name, distribution, version = _names()
    base = f"{distribution}-{version}"
    filename = f"{base}.tar.gz"
    sources = [ROOT / relative for relative in SDIST_FILES] + _package_files()
    tests = ROOT / "tests"
    if tests.is_dir():
        sources += sorted(path for path in tests.glob("*.py"))
    with tarfile.open(os.path.join(sdist_directory, filename), "w:gz", format=tarfile.PAX_FORMAT) as archive:
        def add(archive_name: str, data: bytes) -> None:
            info = tarfile.TarInfo(f"{base}/{archive_name}")
            info.size, info.mtime, info.mode = len(data), int(time.mktime(ZIP_TIME + (0, 0, -1))), 0o644
            archive.addfile(info, io.BytesIO(data))
        add("PKG-INFO", _metadata().encode())
        for path in sources:
            if path.is_file():
                add(path.relative_to(ROOT).as_posix(), path.read_bytes())
    return filename
