"""Loads the native module: bundled in the package (the zip), else `mcrecon` on sys.path."""
import importlib

_module = None


def load():
    global _module
    if _module is None:
        try:
            _module = importlib.import_module(".mcrecon", __package__)
        except ImportError:
            _module = importlib.import_module("mcrecon")
    return _module


def get():
    return load()
