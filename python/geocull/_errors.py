"""geocull's exception hierarchy (raised from Rust as well as from Python)."""


class GeocullError(Exception):
    """Base class of every error geocull raises."""


class InputError(GeocullError, ValueError):
    """A bad argument: wrong shape, dtype, value or range. The message starts with the argument's
    name and points at the first offending element."""


class DeviceError(GeocullError, RuntimeError):
    """No usable graphics adapter, or the driver rejected the work. On a machine without a GPU,
    install Mesa's lavapipe: ``apt-get install libvulkan1 mesa-vulkan-drivers``."""


class GeocullWarning(UserWarning):
    """Something valid but almost certainly not what was meant, e.g. a frame that cannot show
    anything because the whole scene lies nearer than the near plane."""
