"""Sphinx configuration of sflm's documentation: the API reference from the numpydoc docstrings, the method, the notebooks.

Built by ``python docs/build.py OUT`` (and by ``tests/test_docs_build.py``, warnings as errors). The notebooks are
rendered as they are stored (CI executes them, `pytest --nbmake notebooks`; the build does not).
"""

project = "sflm"
author = "sflm developers"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.mathjax", "numpydoc", "myst_nb"]
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # the numpydoc sections carry the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
nb_execution_mode = "off"
myst_enable_extensions = ["dollarmath"]
suppress_warnings = ["myst.header"]  # method.md's sections start at level 2 under its title
html_theme = "alabaster"
exclude_patterns = ["_build", "build.py", "conf.py"]
