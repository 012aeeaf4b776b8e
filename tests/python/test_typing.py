"""The package is typed (PEP 561): it ships py.typed, and every public function, method and
property has inline type hints for its parameters and its result."""

import inspect
import os

import softhap


def public_callables():
    """(name, function) of every public function of softhap.__all__ and every public method and
    property of its classes, those inherited from other softhap classes included."""
    for name in softhap.__all__:
        obj = getattr(softhap, name)
        if inspect.isfunction(obj):
            yield name, obj
        if not inspect.isclass(obj):
            continue
        for cls in obj.__mro__:
            if not cls.__module__.startswith("softhap"):
                continue
            for member_name, member in vars(cls).items():
                if member_name.startswith("_") and member_name not in ("__init__", "__enter__", "__exit__"):
                    continue
                if isinstance(member, property):
                    for accessor in (member.fget, member.fset):
                        if accessor is not None:
                            yield "%s.%s" % (name, member_name), accessor
                elif isinstance(member, (classmethod, staticmethod)):
                    yield "%s.%s" % (name, member_name), member.__func__
                elif inspect.isfunction(member):
                    yield "%s.%s" % (name, member_name), member


def test_the_package_has_a_py_typed_marker():
    marker = os.path.join(os.path.dirname(softhap.__file__), "py.typed")
    assert os.path.isfile(marker)
    assert os.path.getsize(marker) == 0


def test_every_public_callable_has_type_hints():
    missing = []
    for name, function in public_callables():
        signature = inspect.signature(function)
        for parameter in signature.parameters.values():
            if parameter.name in ("self", "cls"):
                continue
            if parameter.annotation is inspect.Parameter.empty:
                missing.append("%s(%s)" % (name, parameter.name))
        if signature.return_annotation is inspect.Signature.empty:
            missing.append("%s -> ?" % name)
    assert missing == []


def test_world_methods_from_its_base_class_are_world_methods():
    # add_tool and friends are defined beside Tool and Obstacle, and inherited by World.
    for name in ("add_tool", "add_obstacle", "set_body_contact", "clear_body_contact"):
        assert callable(getattr(softhap.World, name))
        assert getattr(softhap.World, name).__doc__
