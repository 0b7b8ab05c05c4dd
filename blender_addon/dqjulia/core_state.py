"""What the core says about each object's parameters, the add-on's shared state: the document
validated, its bounds, whether the slice is provably empty (and why), r_K, and the slice's 8-D
axes (slicing.py). The preview draws from it, the panels show its errors, the bakes size their
volumes' density by its bounds, the OSL volume takes its inputs from it and Add DQ Julia sizes the
new empty with it.

Computed once per document on the main thread's own native context and cached by the document's
JSON (at most MAX_STATES; the cache is emptied when a .blend is loaded and when the add-on is
unregistered). Modules import this one, never each other, for it. The running bakes are jobs.py's
(jobs.active_jobs()), the preview's shaders and viewport textures preview.py's own.
"""

import json

import bpy

from . import native, props, slicing

MAX_STATES = 64
_states = {}  # document JSON -> State
_context = None  # the main thread's native context for validation and inspection


class State:
    """The validated parameters of one document and what the add-on derives from them."""

    def __init__(self, document, text):
        self.document = document
        self.text = text
        self.error = None  # the core's validation message, or why the library is unusable
        self.empty_reason = ""  # why nothing can be seen (slice proven empty, bounds missing)
        self.inspect = None
        self.bounds = None  # (center, radius, clipped)
        self.origin = None
        self.axes = None
        self.stretch = 1.0
        self.containment_radius = 1.0

    @property
    def drawable(self):
        return self.error is None and not self.empty_reason and self.bounds is not None


def _native_context():
    global _context
    if _context is None:
        _context = native.Context()
    return _context


def state_for_document(document):
    text = json.dumps(document, sort_keys=True)
    state = _states.get(text)
    if state is not None:
        return state
    state = State(document, text)
    try:
        context = _native_context()
        context.set_params(document)
        state.inspect = context.inspect()
        bounds = state.inspect.get("bounds")
        if state.inspect.get("empty"):
            state.empty_reason = state.inspect.get("empty_reason") or "the slice is empty"
        if bounds is None:
            state.empty_reason = state.empty_reason or "the slice misses the containment region"
        else:
            state.bounds = (tuple(bounds["center"]), float(bounds["radius"]), bool(bounds.get("clipped")))
        state.containment_radius = float(state.inspect["real"]["containment_radius"])
        state.origin, state.axes = slicing.effective_slice(document)
        state.stretch = slicing.stretch(state.axes)[0]
    except native.NativeUnavailable as error:
        state.error = str(error)
    except native.NativeError as error:
        state.error = error.message
    if len(_states) >= MAX_STATES:
        _states.clear()
    _states[text] = state
    return state


def state_for(obj):
    """The State of an object's current parameters (cached by document)."""
    return state_for_document(props.to_document(obj.dqjulia))


def clear_cache():
    """Forgets every State and closes the native context (a new library loads on next use)."""
    global _context
    _states.clear()
    if _context is not None:
        _context.close()
        _context = None


@bpy.app.handlers.persistent
def _forget_states(*_args):
    """A file was loaded: its objects' States are made anew."""
    _states.clear()


def register():
    if _forget_states not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(_forget_states)


def unregister():
    if _forget_states in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_forget_states)
    clear_cache()
