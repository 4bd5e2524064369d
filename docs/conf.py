"""Sphinx configuration of tapecoil's documentation (`make docs`; output in build/docs).

Built offline from Debian's packages: Sphinx, MyST, furo, jupytext. Before reading the sources
it writes, under docs/_generated/ (git-ignored): the demos as pages (the literate scripts of
demos/, jupytext percent format, converted without running them) and the validation report
(tools/validation_table.py, from the summaries kept in docs/results/). The API reference
imports the package, so the build runs inside the project's environment.
"""

from __future__ import annotations

import dataclasses
import inspect
import re
import shutil
import sys
import types
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"
sys.path.insert(0, str(ROOT / "solver"))
sys.path.insert(0, str(ROOT / "tools"))

import validation_table  # noqa: E402

# `python3 -m tapecoil` runs the command line when its module is imported: autodoc must not
sys.modules.setdefault("tapecoil.__main__", types.ModuleType("tapecoil.__main__"))

import tapecoil  # noqa: E402

project = "tapecoil"
author = "the tapecoil developers"
copyright = "the tapecoil developers, MIT licence"
release = tapecoil.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["results/**", "README.md"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

html_theme = "furo"
html_title = f"tapecoil {release}"
html_static_path: list[str] = []
html_show_sourcelink = False

autosummary_generate = True
# a package's __all__ re-exports its modules' names: document each where it is defined
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_ivar = True
# a Returns section names each value it returns, as Args names the arguments
napoleon_custom_sections = [("Returns", "params_style")]

# MathJax from Debian's libjs-mathjax (2.7) when it is installed, copied into the site (the
# parts that typeset TeX as HTML), so that the equations show without a network; without it
# Sphinx's default loads MathJax from the web.
MATHJAX = Path("/usr/share/javascript/mathjax")
MATHJAX_PARTS = (
    "MathJax.js",
    "config/TeX-AMS_CHTML.js",
    "extensions",
    "jax/input/TeX",
    "jax/output/CommonHTML",
    "jax/element",
    "fonts/HTML-CSS/TeX/woff",
)
if (MATHJAX / "MathJax.js").exists():
    html_static_path = ["_generated/static"]
    mathjax_path = "mathjax/MathJax.js?config=TeX-AMS_CHTML"
    # MathJax 2's configuration (Sphinx's default one is MathJax 3's): typeset Sphinx's math
    mathjax3_config = None
    mathjax2_config = {
        "tex2jax": {
            "inlineMath": [["\\(", "\\)"]],
            "displayMath": [["\\[", "\\]"]],
            "processEscapes": True,
            "ignoreClass": "document",
            "processClass": "math|output_area",
        }
    }


def copy_mathjax() -> None:
    target = GENERATED / "static" / "mathjax"
    if target.exists() or not (MATHJAX / "MathJax.js").exists():
        return
    for part in MATHJAX_PARTS:
        source, destination = MATHJAX / part, target / part
        destination.parent.mkdir(parents=True, exist_ok=True)
        if source.is_dir():
            shutil.copytree(source, destination, symlinks=False)
        else:
            shutil.copyfile(source, destination)


# --- generated pages ----------------------------------------------------------------------


def _write(path: Path, text: str) -> None:
    """Write only when the text changes, so that Sphinx rebuilds only what changed."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def demo_page(script: Path) -> str:
    """A literate demo (jupytext percent format) as a MyST page: its markdown cells as text,
    its code cells as Python blocks, in order; not run."""
    import jupytext

    notebook = jupytext.read(script)
    parts = []
    for cell in notebook.cells:
        source = cell.source.strip("\n")
        if not source:
            continue
        parts.append(source if cell.cell_type == "markdown" else f"```python\n{source}\n```")
    body = "\n\n".join(parts)
    run = f'make run CMD="python3 demos/{script.name}"'
    return f"{body}\n\n*The script: `demos/{script.name}`; run it with `{run}`.*\n"


def attribute_docs(cls) -> dict[str, str]:
    """The ``Attributes:`` section of a class's docstring, by name (continuation lines joined)."""
    docs, name, inside = {}, None, False
    for line in inspect.getdoc(cls).splitlines():
        if line.strip() == "Attributes:":
            inside = True
            continue
        if not inside:
            continue
        if line and not line.startswith(" "):
            break
        match = re.match(r"^    (\w+):\s*(.*)$", line)
        if match:
            name = match.group(1)
            docs[name] = match.group(2)
        elif name and line.strip():
            docs[name] += " " + line.strip()
    return docs


def configuration_page() -> str:
    """Every configuration key: its table, unit, default, allowed values and meaning, read from
    the configuration's dataclasses (what `tapecoil config` checks), so it cannot drift."""
    from tapecoil.config import Config

    out = [
        "# Configuration reference",
        "",
        "Every key of a configuration file, read from the configuration's own definitions",
        "(`tapecoil.config.sections`), which are what `tapecoil config` checks a file against.",
        "Units are SI; `-` is dimensionless. See [](../guide/configure.md) for how to use them.",
        "",
    ]
    defaults = Config()
    for section in dataclasses.fields(Config):
        cls = type(getattr(defaults, section.name))
        out += [f"## `[{section.name}]`", "", inspect.getdoc(cls).split("\n\n")[0], ""]
        out += ["| key | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
        docs = attribute_docs(cls)
        for f in dataclasses.fields(cls):
            allowed = f.metadata.get("allowed")
            if allowed is None:
                allowed_text = ""
            elif isinstance(allowed, tuple):
                allowed_text = ", ".join(f"`{a}`" for a in allowed)
            else:
                allowed_text = allowed.describe()
            default = getattr(getattr(defaults, section.name), f.name)
            default = f"{default:.6g}" if isinstance(default, float) else repr(default)
            meaning = docs.get(f.name, "").replace("|", "\\|")
            out.append(
                f"| `{f.name}` | {f.metadata.get('unit', '')} | `{default}` | {allowed_text} | {meaning} |"
            )
        out.append("")
    return "\n".join(out)


def predictions_page() -> str:
    """The analytic predictions for the benchmark tape, as `tapecoil theory` prints them,
    computed here from `tapecoil.theory` so that the page is what the code says."""
    from tapecoil.config import Config
    from tapecoil.theory.table import predictions

    out = [
        "# The predictions for the benchmark tape",
        "",
        "Every analytic prediction for the default configuration (the benchmark tape), computed by",
        "`tapecoil.theory` when this site was built: what `tapecoil theory` prints. For a",
        "configuration of your own: `tapecoil theory my_tape.toml` (`--json` for the numbers).",
        "",
        "| quantity | value | unit | source |",
        "|---|---|---|---|",
    ]
    for p in predictions(Config()):
        out.append(f"| {p.label} | {p.value:.5g} | {p.unit} | {p.source} |")
    return "\n".join(out) + "\n"


def demo_scripts() -> list[Path]:
    return [p for p in sorted((ROOT / "demos").glob("*.py")) if "jupytext:" in p.read_text()[:400]]


def generate() -> None:
    names = []
    for script in demo_scripts():
        _write(GENERATED / "demos" / f"{script.stem}.md", demo_page(script))
        names.append(script.stem)
    toctree = "\n".join(f"{name}" for name in names)
    _write(
        GENERATED / "demos" / "index.md",
        "# Demos\n\nThe literate scripts of `demos/`, shown as pages: the explanation and the "
        'equations beside the code. Each runs as it is (`make run CMD="python3 demos/NAME.py"`, '
        "or under `mpirun -n 2`), and the tests run every one in a short variant.\n\n"
        f"```{{toctree}}\n:maxdepth: 1\n\n{toctree}\n```\n",
    )
    _write(GENERATED / "configuration.md", configuration_page())
    _write(GENERATED / "predictions.md", predictions_page())
    results = validation_table.load_results()
    _write(GENERATED / "validation.md", validation_table.page(results))
    copy_mathjax()


generate()


# --- docstrings ---------------------------------------------------------------------------
# The package's docstrings are plain text with a few reST roles (:class:, ``code``) and Google
# sections (Args:, Attributes:): formulas with |x|, names ending in _ (prefixes such as coil_)
# and indented formula blocks, which reST would read as substitutions, link targets and block
# quotes. Before napoleon reads them, this makes them what they mean in plain text: bars and
# trailing underscores literal, an indented block after a paragraph a literal block.

SECTIONS = re.compile(
    r"^(Args|Arguments|Attributes|Returns|Yields|Raises|Notes?|Examples?|Parameters|"
    r"Keyword Args|Other Parameters|Methods|Warnings?|See Also|References|Todo):\s*$"
)

LIST_ITEM = re.compile(r"^\s*(\d+[.)]|[-*+]|#\.|\(\w\))\s")


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def plain_text_docstring(lines: list[str]) -> list[str]:
    """The docstring's lines with plain text's bars, underscores and indented blocks made
    literal for reST (see above); Google sections and reST constructs are left as they are."""
    escaped = []
    literal = False  # inside a literal block (after "::"): nothing is escaped there
    base = 0
    for line in lines:
        if literal and line.strip() and _indent(line) <= base:
            literal = False
        if not literal:
            table = line.strip().startswith("+-") or (line.strip()[:1] == "|" and line.strip()[-1:] == "|")
            line = line if table else re.sub(r"(?<!\\)\|", r"\|", line)
            line = re.sub(r"(?<=\w)_(?=[\s,.;:)\]]|$)", r"\_", line)
        escaped.append(line)
        if line.rstrip().endswith("::"):
            literal, base = True, _indent(line)
    out: list[str] = []
    i = 0
    while i < len(escaped):
        line = escaped[i]
        out.append(line)
        nxt = escaped[i + 1] if i + 1 < len(escaped) else ""
        opens_block = (
            line.strip()
            and nxt.strip()
            and _indent(nxt) > _indent(line)
            and not SECTIONS.match(line.strip())
            and not line.lstrip().startswith((":", ".."))
            and not LIST_ITEM.match(line)
            and not line.rstrip().endswith("::")
            and _indent(line) == 0
        )
        after_blank = (
            not line.strip()
            and nxt.strip()
            and _indent(nxt) > 0
            and out[:-1]
            and out[-2].strip()
            and _indent(out[-2]) == 0
            and not SECTIONS.match(out[-2].strip())
            and not out[-2].lstrip().startswith((":", ".."))
            and not LIST_ITEM.match(out[-2])
            and not out[-2].rstrip().endswith("::")
        )
        if opens_block or after_blank:
            # the block that follows, to the next line back at the paragraph's indent
            if opens_block:
                out[-1] = line.rstrip()[:-1] + "::" if line.rstrip().endswith(":") else line
                if not out[-1].endswith("::"):
                    out.append("")
                    out.append("::")
                out.append("")
            else:
                previous = out[-2].rstrip()
                out[-2] = previous[:-1] + "::" if previous.endswith(":") else previous
                if not out[-2].endswith("::"):
                    out.insert(len(out) - 1, "")
                    out.insert(len(out) - 1, "::")
            j = i + 1
            while j < len(escaped) and (not escaped[j].strip() or _indent(escaped[j]) > 0):
                out.append(escaped[j].replace("\\|", "|").replace("\\_", "_"))
                j += 1
            if j < len(escaped):
                out.append("")
            i = j
            continue
        i += 1
    return out


def _process_docstring(app, what, name, obj, options, lines):
    lines[:] = plain_text_docstring(lines)


def setup(app):
    app.connect("autodoc-process-docstring", _process_docstring, priority=400)
