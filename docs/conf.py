"""Sphinx configuration of sflm's documentation: the API reference from the numpydoc docstrings, the method, the notebooks.

Built by ``python docs/build.py OUT`` (and by ``tests/integration/test_docs_build.py``, warnings as errors). The notebooks are
rendered as they are stored (CI executes them, `pytest --nbmake notebooks`; the build does not).
"""

project = "sflm"
author = "sflm developers"
copyright = "2026, sflm developers"  # noqa: A001 (Sphinx's name)
# MathJax served from the built site (sphinx-mathjax-offline copies it into _static): the math renders offline
extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "sphinx.ext.intersphinx", "sphinx.ext.mathjax",
              "sphinx-mathjax-offline", "numpydoc", "myst_nb"]
autosummary_generate = False  # the summary tables link to the entries documented on the same page
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"  # the numpydoc sections carry the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
nb_execution_mode = "off"
myst_enable_extensions = ["dollarmath"]
suppress_warnings = ["myst.header"]  # method.md's sections start at level 2 under its title
# furo: a content column that code blocks and outputs scroll within, a layout for phones, a light and a dark scheme
html_theme = "furo"
html_title = "sflm"
html_static_path = ["_static"]
html_css_files = ["sflm.css"]
html_js_files = [("sflm.js", {"defer": "defer"})]  # display equations scaled to the column (a phone's 390 px)
html_favicon = "_static/favicon.svg"  # a hub and its link: no 404 on every page  # notebook outputs wrap, display math scrolls within the column
# the CLI reference and the guides quote flags: "--flag" stays two hyphens, never an en dash
smartquotes = False
exclude_patterns = ["_build", "_static", "build.py", "conf.py", "inventories"]

# Links to the libraries sflm's functions take and return. Each site's own inventory is asked for first; without a
# network (CI, offline) the copy in docs/inventories/ answers (its README says where each comes from), so a strict build
# offline links as one online does. The addresses name the versions those copies were read from.
_INVENTORIES = __import__("pathlib").Path(__file__).resolve().parent / "inventories"
intersphinx_mapping = {
    name: (url, (None, str(_INVENTORIES / f"{name}.inv")))
    for name, url in {
        "python": "https://docs.python.org/3/",
        "numpy": "https://numpy.org/doc/2.2/",
        "scipy": "https://docs.scipy.org/doc/scipy-1.15.3/",
        "sympy": "https://docs.sympy.org/latest/",
        "control": "https://python-control.readthedocs.io/en/0.10.2/",
        "casadi": "https://web.casadi.org/python-api/",
    }.items()
}
intersphinx_timeout = 5  # seconds per site: a network that drops packets costs the build half a minute, not ten
# numpydoc links the types of the Parameters and Returns sections: the names docstrings write, to their objects
numpydoc_xref_param_type = True
numpydoc_xref_aliases = {
    "ArrayLike": "numpy.typing.ArrayLike",
    "NDArray": "numpy.typing.NDArray",
    "FloatArray": "numpy.typing.NDArray",
    "ndarray": "numpy.ndarray",
    "Path": "pathlib.Path",
    "Mapping": "collections.abc.Mapping",
    "Sequence": "collections.abc.Sequence",
    "Iterable": "collections.abc.Iterable",
    "callable": "collections.abc.Callable",
    "sympy.Matrix": "sympy.matrices.dense.Matrix",
    "sympy.Symbol": "sympy.core.symbol.Symbol",
    "sympy.Expr": "sympy.core.expr.Expr",
}
numpydoc_xref_ignore = {"or", "of", "optional", "default", "shape", "to", "and", "the", "a", "an", "one", "per", "each",
                        "same", "as", "with", "in"}


def resolves(name):  # noqa: ANN001, ANN201
    """Whether a dotted name (``inversion.family.ssef.basis.exponents``, ``modelgen.Model``) is an object of the code: the
    longest importable module, then attributes."""
    import importlib

    import inversion

    parts = name.split(".")
    if any(".".join(parts[:cut]) in inversion.MOVED for cut in range(1, len(parts) + 1)):
        return False  # a module's old name: it imports (with a DeprecationWarning) for a release, and is stale in the docs
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return False
        return True
    return False


def check_code_table(app, docname, source):  # noqa: ANN001, ANN201 (Sphinx's event)
    """Every dotted name in ``method.md``'s paper-to-code table (its section 8) names an object of the code: a function
    renamed or moved without the table is a warning, which the strict build makes an error."""
    import re

    from sphinx.util import logging

    if docname != "method/reference":  # docs/build.py puts method.md's section 8 on this page
        return
    text = source[0]
    start = text.find("## 8. From the paper's equations to the code")
    table = text[start:text.find("\n## ", start + 4)] if start >= 0 else ""
    if not table:
        logging.getLogger(__name__).warning("method.md has no section 8 (the paper-to-code table)", location=docname)
    for name in re.findall(r"`((?:modelgen|inversion|simulation)(?:\.\w+)+)`", table):
        if not resolves(name):
            logging.getLogger(__name__).warning(f"method.md's paper-to-code table names {name}, which is not in the code",
                                                location=docname)


def setup(app):  # noqa: ANN001, ANN201 (Sphinx's hook)
    """numpydoc (1.11) builds a Jinja environment and compiles its docstring template for each of the ~970 docstrings
    (4.7 s of a 26 s build); the template is the same throughout, so it is compiled once in the process. Without the
    module attribute this relies on (another numpydoc), the build is as numpydoc makes it."""
    import numpydoc.docscrape_sphinx as sphinx_docstrings

    app.connect("source-read", check_code_table)
    base = getattr(sphinx_docstrings, "SandboxedEnvironment", None)
    if base is None:
        return {"parallel_read_safe": True}

    class OneTemplate(base):
        compiled: dict = {}

        def get_template(self, name, parent=None, globals=None):  # noqa: A002 (Jinja's signature)
            if globals:  # numpydoc passes none; a caller's globals get their own template
                return super().get_template(name, parent, globals)
            if (name, parent) not in self.compiled:
                self.compiled[(name, parent)] = super().get_template(name, parent)
            return self.compiled[(name, parent)]

    sphinx_docstrings.SandboxedEnvironment = OneTemplate
    return {"parallel_read_safe": True}
