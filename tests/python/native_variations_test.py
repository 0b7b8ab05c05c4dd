"""The ctypes bindings of the variations (python/dqjulia/_native.py) against the built library,
as the Blender add-on calls them: the feature is there, the same seed gives the same documents,
each one a complete document a context takes back unchanged, the locked groups stay, the
report's counts add up, and bad settings, an empty start and a cancel raise the classes of
their status with the library's message.

Usage: python3 tests/python/native_variations_test.py SOURCE_DIR LIBRARY
"""

import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
from check_report import report  # noqa: E402 (tests/common/check_report.py)


def raised(call, error_class):
    """The message of the `error_class` that `call()` raised, or None."""
    try:
        call()
    except error_class as error:
        return str(error)
    except Exception:
        return None
    return None


def main():
    source, library = sys.argv[1:3]
    os.environ["DQJULIA_LIBRARY"] = library
    sys.path.insert(0, os.path.join(source, "python"))
    from dqjulia import _native as native

    checks = {"the library has the feature variations": native.has_feature(native.FEATURE_VARIATIONS)}
    with native.Context() as context:
        start = context.params()
        documents = []
        for _ in range(2):
            context.set_params(start)
            context.variations_compute(3, native.STRENGTHS["small"], native.GROUP_A | native.GROUP_VARIANT, 4)
            documents.append([context.variation_params_json(index) for index in range(4)])
        checks["the same seed, the same documents"] = documents[0] == documents[1]
        summary = context.variations()
        rejected = sum(summary["rejected"].values())
        checks["the report: 4 variations, candidates = kept + rejected (%s)" % summary] = (
            summary["count"] == 4 and summary["candidates"] == 4 + rejected and len(summary["variations"]) == 4
        )
        for index, text in enumerate(documents[0]):
            document = json.loads(text)
            checks["variation %d keeps a" % index] = document["fractal"]["c"][:4] == start["fractal"]["c"][:4]
            checks["variation %d changes b" % index] = document["fractal"]["c"][4:] != start["fractal"]["c"][4:]
            context.set_params_json(text)
            checks["variation %d is a complete document, taken back unchanged" % index] = context.params_json() == text
        context.set_params(start)
        message = raised(lambda: context.variations_compute(1, 1.5), native.InvalidArgumentError)
        checks["strength 1.5: InvalidArgumentError (%s)" % message] = message is not None and "strength" in message
        message = raised(lambda: context.variations_compute(1, 0.3, native.GROUP_ALL), native.InvalidArgumentError)
        checks["all locked: InvalidArgumentError (%s)" % message] = message is not None and "locked" in message
        progress = native.Progress()
        progress.cancel()
        message = raised(lambda: context.variations_compute(1, progress=progress), native.CancelledError)
        checks["cancelled: CancelledError (%s)" % message] = message is not None
        context.set_params({"fractal": {"c": [-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64]}})
        message = raised(lambda: context.variations_compute(1), native.ParameterError)
        checks["an empty start: ParameterError (%s)" % message] = message is not None and "itself empty" in message
    return report(checks)


if __name__ == "__main__":
    sys.exit(main())
