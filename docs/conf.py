"""Sphinx configuration of the dqjulia documentation site (docs/, built by scripts/build-docs.sh)."""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "python"))  # autodoc imports the package (it loads the library lazily)
sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))

project = "dqjulia"
author = "the dqjulia authors"
release = (ROOT / "VERSION").read_text(encoding="utf-8").strip()
version = release
# Sphinx takes the year from SOURCE_DATE_EPOCH when it is set (scripts/release.sh sets it).
copyright = "the dqjulia authors"

extensions = ["myst_parser", "sphinx.ext.autodoc", "dqj_reference"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "_ext"]
# Headings up to level 4 get GitHub-style anchors, so [text](page.md#a-heading) links are checked.
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]
# Every warning is an error under -W: a link or anchor that does not resolve is one.
nitpicky = False
suppress_warnings: list = []

autodoc_member_order = "bysource"
autodoc_typehints = "description"

html_theme = "furo"
html_title = f"dqjulia {release}"
html_static_path: list = []
html_last_updated_fmt = None
html_copy_source = False
html_show_sourcelink = False

dqj_cli = os.environ.get("DQJ_CLI", "")
