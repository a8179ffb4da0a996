"""A designer's learned style (docs/STYLE_FORMAT.md): :func:`learn` fits a :class:`Style` to films a
designer edited (their cached analyses and edited timelines), ``pipeline.derive(analysis, params,
style=style)`` applies one without decoding (``style.apply_params(params)`` before the derive,
``style.shape(...)`` on its tracks), :func:`load` / :func:`save` / :func:`from_dict` /
:func:`to_dict` read and write the checked JSON document, :func:`explain` says how much of each
film's edits a style explains.
"""

from autohaptics.lazy import lazy_attributes
from autohaptics.style.model import FORMAT, KNOTS, VERSION, Style, check, from_dict, load, save, to_dict

__getattr__ = lazy_attributes(__name__, {"learn": "fit", "fit_curve": "fit", "explain": "report"})

__all__ = ["FORMAT", "KNOTS", "VERSION", "Style", "check", "explain", "fit_curve", "from_dict", "learn", "load", "save",
           "to_dict"]
