"""Every public class, function, method and property of the package has a docstring."""

import inspect

import softhap


def public_objects():
    for name in softhap.__all__:
        obj = getattr(softhap, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            yield name, obj
        if inspect.isclass(obj) and obj.__module__.startswith("softhap"):
            for member_name, member in vars(obj).items():
                if member_name.startswith("_") and member_name not in ("__init__", "__enter__", "__exit__", "__del__"):
                    continue
                if isinstance(member, (property, classmethod, staticmethod)) or inspect.isfunction(member):
                    yield "%s.%s" % (name, member_name), member


def test_every_public_object_has_a_docstring():
    missing = []
    for name, obj in public_objects():
        target = obj.__func__ if isinstance(obj, (classmethod, staticmethod)) else obj
        doc = getattr(target, "__doc__", None)
        if not doc or not doc.strip():
            missing.append(name)
    assert missing == []


def test_module_docstring():
    assert "SOFTHAP_LIBRARY" in softhap.__doc__
