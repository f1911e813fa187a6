# SPDX-License-Identifier: Apache-2.0
"""The PEP 517 build backend of elaslam-msgs (python/pyproject.toml): a pure-Python
wheel of the package `elaslam`, the message types lcm-gen writes from lcmtypes/*.lcm
(the one source of truth). Standard library only, so that `pip install` needs neither
setuptools nor wheel nor a network. Two places it builds from:

- the source tree, `pip install ./python`: this file beside ../lcmtypes/; lcm-gen
  (Debian's liblcm-bin; $ELASLAM_LCM_GEN names another) writes the types into a
  scratch folder for the wheel, and the version is the project() line of
  ../CMakeLists.txt;
- the build tree, `pip install ./build/python`: the types beside this file (copied
  there by the build, lcmtypes/CMakeLists.txt) and the version in the file VERSION.

Metadata from pyproject.toml's [project] table. Nothing is written beside this file."""
import base64
import glob
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import zipfile

try:
    import tomllib  # Python >= 3.11
except ImportError:  # pragma: no cover - older Pythons
    try:
        import tomli as tomllib
    except ImportError:
        tomllib = None

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = "elaslam"
# A fixed time stamp: the same inputs give the same wheel, byte for byte.
ZIP_TIME = (2020, 1, 1, 0, 0, 0)


def _in_build_tree():
    return os.path.isfile(os.path.join(HERE, PACKAGE, "__init__.py"))


def _lcm_defs():
    return sorted(glob.glob(os.path.join(HERE, "..", "lcmtypes", "*.lcm")))


def _version():
    if _in_build_tree():
        with open(os.path.join(HERE, "VERSION"), encoding="utf-8") as f:
            return f.read().strip()
    cmake = os.path.join(HERE, "..", "CMakeLists.txt")
    try:
        with open(cmake, encoding="utf-8") as f:
            m = re.search(r"project\(\s*elaslam\s+VERSION\s+([0-9][0-9.]*)", f.read())
    except OSError as e:
        raise RuntimeError(f"elaslam-msgs: no version: {e} (install ./python from a clone of the project, "
                           f"or ./build/python after a build)") from None
    if not m:
        raise RuntimeError(f"elaslam-msgs: {cmake} has no 'project(elaslam VERSION x.y.z' line")
    return m.group(1)


def _project():
    path = os.path.join(HERE, "pyproject.toml")
    if tomllib is None:
        raise RuntimeError("elaslam-msgs: building needs Python >= 3.11 (tomllib) or the tomli module")
    with open(path, "rb") as f:
        project = dict(tomllib.load(f)["project"])
    if "version" in project.get("dynamic", []):
        project["version"] = _version()
    return project


def _generate(scratch):
    """lcm-gen's Python output for ../lcmtypes/*.lcm in scratch/elaslam/."""
    defs = _lcm_defs()
    if not defs:
        raise RuntimeError(f"elaslam-msgs: no {PACKAGE}/ beside {HERE} and no ../lcmtypes/*.lcm: install ./python "
                           f"from a clone of the project, or ./build/python after `cmake --build build`")
    gen = os.environ.get("ELASLAM_LCM_GEN") or shutil.which("lcm-gen")
    if not gen:
        raise RuntimeError("elaslam-msgs: lcm-gen not found (Debian: sudo apt-get install liblcm-bin; "
                           "or set ELASLAM_LCM_GEN), or install ./build/python after `cmake --build build`")
    r = subprocess.run([gen, "--python", "--ppath", scratch] + defs, capture_output=True, text=True)
    if r.returncode != 0 or not os.path.isfile(os.path.join(scratch, PACKAGE, "__init__.py")):
        raise RuntimeError(f"elaslam-msgs: {gen} --python failed (exit {r.returncode}): {r.stderr.strip()}")
    return scratch


def _dist_name(project):
    return project["name"].replace("-", "_")


def _metadata(project):
    lines = ["Metadata-Version: 2.1", f"Name: {project['name']}", f"Version: {project['version']}",
             f"Summary: {project.get('description', '')}"]
    if "requires-python" in project:
        lines.append(f"Requires-Python: {project['requires-python']}")
    license_ = project.get("license", {})
    if isinstance(license_, dict) and "text" in license_:
        lines.append(f"License: {license_['text']}")
    lines += [f"Requires-Dist: {d}" for d in project.get("dependencies", [])]
    return "\n".join(lines) + "\n"


def _wheel_text():
    return "Wheel-Version: 1.0\nGenerator: elaslam_msgs_build\nRoot-Is-Purelib: true\nTag: py3-none-any\n"


def _package_files(base):
    root = os.path.join(base, PACKAGE)
    return sorted(f"{PACKAGE}/{n}" for n in os.listdir(root) if n.endswith(".py"))


def _digest(data):
    return "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()


def _write_dist_info(directory, project):
    info = os.path.join(directory, f"{_dist_name(project)}-{project['version']}.dist-info")
    os.makedirs(info, exist_ok=True)
    for name, text in (("METADATA", _metadata(project)), ("WHEEL", _wheel_text()), ("top_level.txt", PACKAGE + "\n")):
        with open(os.path.join(info, name), "w", encoding="utf-8") as f:
            f.write(text)
    return os.path.basename(info)


# ---- PEP 517 hooks ---------------------------------------------------------------
def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    return _write_dist_info(metadata_directory, _project())


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    project = _project()
    dist = _dist_name(project)
    info = f"{dist}-{project['version']}.dist-info"
    name = f"{dist}-{project['version']}-py3-none-any.whl"
    entries = []
    with tempfile.TemporaryDirectory(prefix="elaslam-msgs-") as scratch:
        base = HERE if _in_build_tree() else _generate(scratch)
        for rel in _package_files(base):
            with open(os.path.join(base, rel), "rb") as f:
                entries.append((rel, f.read()))
    entries += [(f"{info}/METADATA", _metadata(project).encode()), (f"{info}/WHEEL", _wheel_text().encode()),
                (f"{info}/top_level.txt", (PACKAGE + "\n").encode())]
    record = "".join(f"{rel},{_digest(data)},{len(data)}\n" for rel, data in entries) + f"{info}/RECORD,,\n"
    entries.append((f"{info}/RECORD", record.encode()))
    os.makedirs(wheel_directory, exist_ok=True)
    with zipfile.ZipFile(os.path.join(wheel_directory, name), "w", zipfile.ZIP_DEFLATED) as z:
        for rel, data in entries:
            zi = zipfile.ZipInfo(rel, ZIP_TIME)
            zi.external_attr = 0o644 << 16
            zi.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(zi, data)
    return name
