"""geocull's exception hierarchy, defined in the extension (src/python/errors.rs, so that Rust raises
the classes directly) and re-exported here and by ``geocull``:

- ``GeocullError(Exception)``: the base class of every error geocull raises;
- ``InputError(GeocullError, ValueError)``: a bad argument;
- ``DeviceError(GeocullError, RuntimeError)``: no usable adapter, or the driver rejected the work;
- ``GeocullWarning(UserWarning)``: something valid but almost certainly not what was meant.

Their ``__module__`` is ``geocull._geocull``; pickles made when they were defined in this module
(``geocull._errors.InputError``) still load, through these names.
"""

from ._geocull import DeviceError, GeocullError, GeocullWarning, InputError

__all__ = ["GeocullError", "InputError", "DeviceError", "GeocullWarning"]
