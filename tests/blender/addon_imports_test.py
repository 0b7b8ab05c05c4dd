"""The add-on's modules import each other without a cycle, and the state they share comes from
core_state.py (CONTRIBUTING.md, "The Blender add-on's modules"): no module but core_state.py
keeps the core's per-document cache or a native context of its own at module level, and none
reaches into preview.py for it. Read from the source (ast), so no Blender is needed.

Usage: python3 addon_imports_test.py SOURCE
"""

import ast
import glob
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)

SHARED = "core_state"
# What core_state.py holds, and may be held nowhere else.
SHARED_NAMES = ("_states", "_context", "state_for", "state_for_document", "clear_cache", "State")


def imports_of(tree, modules):
    """The add-on modules a module imports (`from . import a, b`, `from .a import x`), at any depth."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module is None:
                found.update(alias.name for alias in node.names if alias.name in modules)
            elif node.module in modules:
                found.add(node.module)
    return found


def cycle(graph):
    """One import cycle as a list of modules, or None."""
    done, path = set(), []

    def visit(module):
        if module in path:
            return path[path.index(module) :] + [module]
        if module in done:
            return None
        path.append(module)
        for imported in sorted(graph.get(module, ())):
            found = visit(imported)
            if found:
                return found
        path.pop()
        done.add(module)
        return None

    for module in sorted(graph):
        found = visit(module)
        if found:
            return found
    return None


def main():
    folder = os.path.join(sys.argv[1], "blender_addon", "dqjulia")
    sources = {os.path.splitext(os.path.basename(path))[0]: path for path in glob.glob(os.path.join(folder, "*.py"))}
    modules = set(sources) | {"native"}  # native.py: the packaging's copy of python/dqjulia/_native.py
    trees = {}
    for name, path in sources.items():
        with open(path, encoding="utf-8") as file:
            trees[name] = ast.parse(file.read(), path)
    graph = {name: imports_of(tree, modules) - {name} for name, tree in trees.items()}
    found = cycle(graph)
    checks = {
        "the add-on has %s" % SHARED: SHARED in trees,
        "the add-on's modules import each other without a cycle%s"
        % (" (found %s)" % " -> ".join(found) if found else ""): found is None,
    }
    for name, tree in sorted(trees.items()):
        if name == SHARED:
            continue
        defined = set()
        for node in tree.body:
            if isinstance(node, ast.Assign):
                defined.update(target.id for target in node.targets if isinstance(target, ast.Name))
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                defined.add(node.target.id)
            elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                defined.add(node.name)
        held = [symbol for symbol in defined if symbol in SHARED_NAMES]
        checks["%s.py keeps none of %s's state (%s)" % (name, SHARED, ", ".join(held) or "none")] = not held
        reached = sorted(
            {
                node.attr
                for node in ast.walk(tree)
                if isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id == "preview"
                and node.attr in SHARED_NAMES
            }
        )
        checks["%s.py takes no shared state from preview.py (%s)" % (name, ", ".join(reached) or "none")] = not reached
    # The graph is what the check above walked: show it, so a new edge is seen in the log.
    for name in sorted(graph):
        print("%s imports %s" % (name, ", ".join(sorted(graph[name])) or "nothing of the add-on"))
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
