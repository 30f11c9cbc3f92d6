"""What the Python-module tests share: the module from MCRECON_PYTHON_DIR and expect_error."""
import os
import sys

sys.path.insert(0, os.environ["MCRECON_PYTHON_DIR"])
import mcrecon  # noqa: E402


def expect_error(fn, kind, *words):
    """fn() must raise mcrecon.Error of this kind whose message names every word; returns it."""
    try:
        fn()
    except mcrecon.Error as e:
        msg = str(e)
        assert e.kind == kind, f"kind {e.kind!r}, expected {kind!r} ({msg})"
        for w in words:
            assert w in msg, f"error message {msg!r} does not name {w!r}"
        assert isinstance(e, RuntimeError)  # mcrecon.Error derives from it
        return msg
    raise AssertionError(f"no mcrecon.Error (expected {kind}: {words})")
