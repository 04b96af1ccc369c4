"""Empty stand-ins for Python packages a reference implementation imports but the part of it a
reference script runs does not use (netcal's PyTorch and Pyro, TIDE's OpenCV and pandas), so that
the reference runs unmodified without them. For scripts/*_reference_cases.py only.

    import stub_modules
    stub_modules.install(["torch", "pyro"])   # before importing the reference
"""

import importlib.machinery
import sys
import types


class _Stub(types.ModuleType):
    """A module that has every attribute (each another stub), can be called and be a base class."""

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        m = _Stub(f"{self.__name__}.{name}")
        m.__path__ = []
        sys.modules[m.__name__] = m
        return m

    def __call__(self, *args, **kwargs):
        return self

    def __mro_entries__(self, bases):
        return (object,)


class _StubFinder:
    def __init__(self, names):
        self.names = set(names)

    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in self.names:
            return importlib.machinery.ModuleSpec(name, self)
        return None

    def create_module(self, spec):
        m = _Stub(spec.name)
        m.__path__ = []
        return m

    def exec_module(self, module):
        pass


def install(names):
    """Every later import of one of `names` (top-level package names), or of a module inside one,
    gets a stand-in."""
    sys.meta_path.insert(0, _StubFinder(names))
