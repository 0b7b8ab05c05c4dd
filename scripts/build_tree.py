"""What the release's scripts (dist.py, build-wheels.py) ask of a CMake build tree of this
checkout: its cache's variables, and that it is a build of this source tree for one system.
A module of scripts/, imported by the scripts beside it."""

import re
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


def system_of(build):
    """The system BUILD is for (CMAKE_SYSTEM_NAME: Linux, Windows). A toolchain file sets it as a
    plain variable, which the cache does not hold: CMake records it in CMakeFiles/<its version>/
    CMakeSystem.cmake."""
    cache_value(build, "CMAKE_HOME_DIRECTORY")  # a build tree at all
    for path in sorted(Path(build).glob("CMakeFiles/*/CMakeSystem.cmake")):
        found = re.search(r'^set\(CMAKE_SYSTEM_NAME "([^"]+)"\)', path.read_text(encoding="utf-8"), re.M)
        if found:
            return found.group(1)
    raise BuildTreeError("%s is not a configured build tree (no CMakeFiles/*/CMakeSystem.cmake)" % build)


def check_build(build, system):
    """BUILD is a build tree of this source tree for `system` (CMAKE_SYSTEM_NAME: Linux, Windows)."""
    found = system_of(build)
    if found != system:
        raise BuildTreeError("%s is a build for %s, not for %s" % (build, found, system))
    home = cache_value(build, "CMAKE_HOME_DIRECTORY")
    if home is None or Path(home).resolve() != SOURCE:
        raise BuildTreeError("%s is a build of %s, not of this source tree %s" % (build, home, SOURCE))
