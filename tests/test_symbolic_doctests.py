"""The docstring examples of the symbolic layer, run on the installed package.

pytest collects the doctests of ``quadland/`` from its files (``testpaths``);
``symbolic/`` is installed as ``quadland_symbolic`` (``pyproject.toml``), so its
examples run here on the modules by that name, not on a second copy imported
from the folder.
"""

import doctest
import importlib
import pkgutil

import pytest

import quadland_symbolic

MODULES = sorted(m.name for m in pkgutil.walk_packages(quadland_symbolic.__path__,
                                                       "quadland_symbolic."))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    flags = doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS
    result = doctest.testmod(module, optionflags=flags, report=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed"
