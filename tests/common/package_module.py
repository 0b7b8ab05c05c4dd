"""Loads one module of a package folder as its package's member, without running the folder's
__init__ (the add-on's needs bpy): a stand-in package over the folder answers the module's
relative imports (`from . import _buildinfo`) from the files beside it, as Blender's and pip's
imports do. Used by the tests that load the bindings (native.py, _native.py) outside a host.
Self-contained: the clean-room test copies it into a root beside bake_with_native.py."""

import importlib.util
import os
import sys
import types


def load_package_module(path, package_name):
    """The module at `path` as `package_name.<its name>`, its package a stand-in over its folder."""
    package = types.ModuleType(package_name)
    package.__path__ = [os.path.dirname(os.path.abspath(path))]
    sys.modules[package_name] = package
    name = "%s.%s" % (package_name, os.path.splitext(os.path.basename(path))[0])
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
