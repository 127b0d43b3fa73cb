"""The library's words in the command line's: keywords as flags (:func:`in_flags`), warnings on one line."""

from __future__ import annotations
__all__ = ["FLAGS", "in_flags", "one_line_warning"]

#: The library's keywords and the command line's flags that set them: the library's messages speak Python, the command
#: line's speak flags (:func:`in_flags`).
FLAGS = {
    "max_error": "--max-error", "max_torque": "--max-torque", "max_torque_rate": "--max-torque-rate", "max_deflection": "--max-deflection", "method": "--method", "margin": "--margin",
    "end": "--end", "settings": "--settings", "trajectory": "--trajectory", "modes": "--modes", "mode_shapes": "--mode-shapes",
    "output_at": "--output-at", "rate": "--rate", "period": "--period", "hold": "--hold", "window": "--window", "eps": "--eps",
    "tol": "--tol", "joining": "--joining", "segments": "--segments", "h": "--h", "cdec": "--cdec", "objective": "--objective",
    "zeros": "--zeros", "prefix": "--c-prefix", "uncertainty": "--uncertainty", "samples": "--samples", "workers": "--workers",
    "scheduler": "--scheduler", "smoothing": "--smooth", "plant": "--plant", "controller": "--controller",
    "friction_compensation": "--friction-compensation", "kp": "--kp", "kd": "--kd", "t_end": "--t-end", "preview": "--preview", "edges": "--edges",
    "auto": "--auto", "feedforward": "--feedforward", "out": "--out", "solver": "--solver",
    "data": "--data", "output": "--output", "law": "--kp, --kd", "gains": "--kp, --kd", "params": "--params",
}


def in_flags(message: str, parameter: str | None = None) -> str:
    """A library message in the command line's words.

    A library message in the command line's words: ``method='stable'`` as ``--method stable``, ``auto=True`` as
    ``--auto``, ``max_error`` as ``--max-error``, and the refused ``parameter`` (a keyword) as its flag.

    Only keywords that are flags are rewritten, and bare words only where they hold an underscore (``max_error``), never an
    English word (``end``, ``method``) standing alone.

    Parameters
    ----------
    message : str
        The library's message.
    parameter : str, optional
        The keyword it refuses.
    """
    import re

    if parameter is not None and parameter in FLAGS:
        message = message.replace(f"{parameter} = ", f"{FLAGS[parameter]} = ", 1)

    def assignment(match: re.Match[str]) -> str:
        flag, value = FLAGS[match["name"]], match["value"]
        if value == "True":
            return flag
        return f"{flag} {value.strip(chr(39) + chr(34))}"

    names = "|".join(sorted(map(re.escape, FLAGS), key=len, reverse=True))
    # not after a colon: FILE.csv:smoothing=S is a trajectory's own syntax, in Python and on the command line alike
    message = re.sub(rf"(?<![\w.:-])(?P<name>{names})=(?P<value>'[^']*'|\"[^\"]*\"|[\w.+-]+)", assignment, message)
    underscored = "|".join(re.escape(k) for k in sorted(FLAGS, key=len, reverse=True) if "_" in k)
    return re.sub(rf"(?<![\w.-])({underscored})(?![\w=])", lambda m: FLAGS[m[1]], message)


def one_line_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int, line: str | None = None) -> str:
    """A warning as the command line prints it: one line.

    In the command line's words; :func:`warnings.formatwarning`'s signature.

    Parameters
    ----------
    message : Warning or str
        The warning.
    category : type
        Its category.
    filename : str
        Where it was raised.
    lineno : int
        Its line.
    line : str, optional
        The source line.
    """
    return f"sflm: warning: {in_flags(str(message))}\n"
