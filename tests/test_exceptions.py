"""geocull's exception classes: defined in the extension (src/python/errors.rs), the same objects as
``geocull.InputError`` etc. and ``geocull._errors``'s, with the bases, docstrings and pickling they
had when they were Python classes."""

import pickle
import sys
import warnings

import pytest

import geocull as gc
import geocull._errors as errors_module
import geocull._geocull as ext

BASES = {
    "GeocullError": (Exception,),
    "InputError": (gc.GeocullError, ValueError),
    "DeviceError": (gc.GeocullError, RuntimeError),
    "GeocullWarning": (UserWarning,),
}


@pytest.mark.parametrize("name", sorted(BASES))
def test_classes_come_from_the_extension_and_keep_their_bases(name):
    cls = getattr(gc, name)
    assert cls is getattr(ext, name) is getattr(errors_module, name)
    assert (cls.__module__, cls.__qualname__) == ("geocull._geocull", name)
    assert cls.__bases__ == BASES[name]
    assert name in ext.__all__ and name in gc.__all__


def test_isinstance_relations():
    assert issubclass(gc.InputError, ValueError) and issubclass(gc.InputError, gc.GeocullError)
    assert issubclass(gc.DeviceError, RuntimeError) and issubclass(gc.DeviceError, gc.GeocullError)
    assert not issubclass(gc.GeocullWarning, gc.GeocullError) and issubclass(gc.GeocullWarning, UserWarning)
    assert not issubclass(gc.InputError, RuntimeError) and not issubclass(gc.DeviceError, ValueError)
    assert gc.InputError.__mro__[1:3] == (gc.GeocullError, ValueError)


def test_docstrings_as_before():
    assert gc.GeocullError.__doc__ == "Base class of every error geocull raises."
    assert gc.InputError.__doc__ == (
        "A bad argument: wrong shape, dtype, value or range. The message starts with the argument's\n"
        "    name and points at the first offending element.")
    assert gc.DeviceError.__doc__ == (
        "No usable graphics adapter, or the driver rejected the work. On a machine without a GPU,\n"
        "    install Mesa's lavapipe: ``apt-get install libvulkan1 mesa-vulkan-drivers``.")
    assert gc.GeocullWarning.__doc__ == (
        "Something valid but almost certainly not what was meant, e.g. a frame that cannot show\n"
        "    anything because the whole scene lies nearer than the near plane.")


def test_the_core_raises_the_extension_class():
    with pytest.raises(gc.InputError) as e:
        gc.Scene().remove(5)
    assert type(e.value) is ext.InputError
    assert str(e.value) == "id: no object with id 5 in this scene"
    with pytest.raises(ValueError):
        gc.Scene().remove(5)


@pytest.mark.skipif(sys.platform != "linux", reason="a backend this platform never has")
def test_the_core_raises_device_error():
    with pytest.raises(gc.DeviceError, match="no graphics adapter found") as e:
        gc.Renderer(8, 8, backend="metal")
    assert type(e.value) is ext.DeviceError and isinstance(e.value, RuntimeError)


@pytest.mark.parametrize("name", sorted(BASES))
def test_pickling(name):
    cls = getattr(gc, name)
    assert pickle.loads(pickle.dumps(cls)) is cls
    err = cls("a message")
    err.add_note("a note")
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is cls and back.args == ("a message",) and back.__notes__ == ["a note"]
    # Pickles made while the classes were defined in geocull/_errors.py name them there; they load.
    old = pickle.dumps(err, protocol=0).replace(b"geocull._geocull", b"geocull._errors")
    assert b"geocull._errors" in old and type(pickle.loads(old)) is cls


def test_raised_error_pickles():
    with pytest.raises(gc.InputError) as e:
        gc.Scene().remove(5)
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is gc.InputError and str(back) == str(e.value)


def test_warning_category():
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        warnings.warn("something odd", gc.GeocullWarning, stacklevel=1)
    assert [x.category for x in w] == [gc.GeocullWarning]
    with warnings.catch_warnings():
        warnings.filterwarnings("error", category=gc.GeocullWarning)
        with pytest.raises(gc.GeocullWarning):
            warnings.warn("something odd", gc.GeocullWarning, stacklevel=1)
