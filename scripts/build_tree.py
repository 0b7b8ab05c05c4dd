"""What the release's scripts (dist.py, build-wheels.py) ask of a CMake build tree of this
checkout: its cache's variables, and that it is a build of this source tree for one system.
A module of scripts/, imported by the scripts beside it."""

from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent


class BuildTreeError(Exception):
    pass


def cache_value(build, name):
    """A variable of BUILD/CMakeCache.txt (None when it has none)."""
    cache = Path(build) / "CMakeCache.txt"
    if not cache.is_file():
        raise BuildTreeError("%s is not a CMake build tree (no CMakeCache.txt)" % build)
    for line in cache.read_text(encoding="utf-8", errors="replace").splitlines():
        key, _, value = line.partition("=")
        if key.split(":")[0] == name:
            return value
    return None


def check_build(build, system):
    """BUILD is a build tree of this source tree for `system` (CMAKE_SYSTEM_NAME: Linux, Windows)."""
    found = cache_value(build, "CMAKE_SYSTEM_NAME") or "Linux"
    if found != system:
        raise BuildTreeError("%s is a build for %s, not for %s" % (build, found, system))
    home = cache_value(build, "CMAKE_HOME_DIRECTORY")
    if home is None or Path(home).resolve() != SOURCE:
        raise BuildTreeError("%s is a build of %s, not of this source tree %s" % (build, home, SOURCE))
