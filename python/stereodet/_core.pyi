# Type stubs of the C++ extension stereodet._core (python/src/*.cc). The documented interface is the
# pure-Python package; these names are its internals unless re-exported there.
__version__: str

class ParseError(ValueError):
    file: str
    line: int
    field: str
    message: str

def _calls_in_progress() -> int: ...
