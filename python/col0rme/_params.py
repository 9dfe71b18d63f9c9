"""The keyword arguments of run(), support() and matirf(), made from the
library's one parameter table (c0_run_conf_param_info): their Python names,
type hints, numpy-style docstrings and the checks that raise TypeError and
ValueError. Nothing here lists a parameter's help or default: they cannot
drift from the C table, the CLI's --help and docs/params.md."""
import ctypes
import inspect
import os
import textwrap
import typing

import numpy as np

# C name -> Python name, where the C name is not a fit Python keyword or lacks its unit
PY_NAME = {"pixel_nm": "pixel_size_nm", "lambda": "lambda_"}
# earlier names that keep working (not shown in the signature)
ALIASES = {"pixel_size": "pixel_size_nm", "pixel_nm": "pixel_size_nm", "fwhm": "fwhm_nm", "lam": "lambda_",
           "lambda": "lambda_"}
# which function takes which (the CLI's commands take the same: tests/install check it)
RAW_MATIRF = ("offset", "matirf_background", "estimate_background", "background_smooth", "psf_fwhm_nm")
SUPPORT = ("pixel_nm", "fwhm_nm", "psf_image", "emission_nm", "na", "srf", "support_pool", "label_radius_nm", "penalty", "lambda", "lambda_rule",
           "fwhm_rule", "iterations", "support_solver", "tol", "reweightings", "lag", "tile", "drift", "pixel_guard",
           "frc", "offset_map", "variance_map", "gain_map")
MATIRF = ("pixel_nm", "angles", "n_glass", "n_sample", "wavelength_nm", "s_fraction", "gains", "z_range_nm", "reg",
          "kappa", "sparsity", "axial_weight", "matirf_iterations", "matirf_tol", "matirf_solver", "matirf_coarse") \
    + RAW_MATIRF

_HINT = {"number": float, "integer": int, "flag": bool, "numbers": typing.Sequence[float],
         "integers": typing.Sequence[int], "file": typing.Union[str, os.PathLike]}
_DOC_TYPE = {"number": "float", "integer": "int", "flag": "bool", "numbers": "sequence of float",
             "integers": "sequence of int", "file": "str or path"}


class Param:
    """One row of the table: C name, Python name, kind, choices, help, default (text)."""

    def __init__(self, cname, kind, choices, help_, default):
        self.cname, self.kind, self.help, self.default = cname, kind, help_, default
        self.name = PY_NAME.get(cname, cname)
        self.choices = tuple(choices.split("|")) if choices else ()
        self.hint = typing.Optional[typing.Literal[self.choices] if self.choices else _HINT[kind]]

    def doc(self):
        t = "{%s}" % ", ".join(repr(c) for c in self.choices) if self.choices else _DOC_TYPE[self.kind]
        text = "%s. Default: %s." % (self.help[:1].upper() + self.help[1:], self.default)
        return "%s : %s, optional\n%s" % (self.name, t, textwrap.fill(text, 79, initial_indent="    ",
                                                                     subsequent_indent="    "))

    def text(self, v):
        """The value as c0_run_conf_set's text; TypeError for a wrong type, ValueError for an unknown choice."""
        k = self.kind
        if self.choices:
            if isinstance(v, bool) and set(self.choices) <= {"on", "off"}:
                return "on" if v else "off"
            if not isinstance(v, str):
                raise TypeError("%s: expected one of %s, got %s" % (self.name, "|".join(self.choices), type(v).__name__))
            if v not in self.choices:
                raise ValueError("%s: %r is not one of %s" % (self.name, v, "|".join(self.choices)))
            return v
        if k == "file":
            if not isinstance(v, (str, os.PathLike)):
                raise TypeError("%s: expected a file path, got %s" % (self.name, type(v).__name__))
            return os.fsdecode(v)
        if k in ("numbers", "integers"):
            if isinstance(v, (str, bytes)) or not isinstance(v, (typing.Sequence, np.ndarray)):
                if not isinstance(v, (int, float, np.number)) or isinstance(v, bool):
                    raise TypeError("%s: expected a sequence of numbers, got %s" % (self.name, type(v).__name__))
                v = [v]
            return ",".join(_number(self.name, x, k == "integers") for x in np.asarray(v).ravel().tolist())
        if k == "flag":
            if not isinstance(v, (bool, np.bool_)) and not (isinstance(v, (int, np.integer)) and v in (0, 1)):
                raise TypeError("%s: expected True or False, got %r" % (self.name, v))
            return "1" if v else "0"
        return _number(self.name, v, k == "integer")


def _number(name, v, integer):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, float, np.integer, np.floating)):
        raise TypeError("%s: expected %s, got %s" % (name, "an int" if integer else "a number", type(v).__name__))
    if integer:
        if isinstance(v, (float, np.floating)) and not float(v).is_integer():
            raise TypeError("%s: expected an int, got %r" % (name, v))
        return str(int(v))
    if not np.isfinite(v):
        raise ValueError("%s: %r is not a finite number" % (name, v))
    return format(float(v), ".17g")


def table(lib):
    """The library's parameters, in the table's order: {Python name: Param}."""
    out, i = {}, 0
    kind, choices, help_, default = (ctypes.c_char_p() for _ in range(4))
    while True:
        name = lib.c0_run_conf_param_info(i, *(ctypes.byref(x) for x in (kind, choices, help_, default)))
        if not name:
            return out
        d = lambda x: x.value.decode() if x.value else ""
        p = Param(name.decode(), d(kind), d(choices), d(help_), d(default))
        out[p.name] = p
        i += 1


def keywords(params, take):
    """The Params a function takes: take(C name) -> bool."""
    return [p for p in params.values() if take(p.cname)]


def signature(head, params, tail):
    """head (positional Parameters), then every parameter keyword-only with default None, then tail."""
    kw = [inspect.Parameter(p.name, inspect.Parameter.KEYWORD_ONLY, default=None, annotation=p.hint) for p in params]
    return inspect.Signature(head + kw + tail)


def docstring(summary, params, extra):
    """summary, then a numpy-style Parameters section: extra (its own lines), then the table's rows."""
    rows = "\n".join(p.doc() for p in params)
    return "%s\n\nParameters\n----------\n%s\n%s\n" % (summary.strip("\n"), extra.strip("\n"), rows)


def bind(func, sig, params, args, kwargs):
    """args/kwargs bound to sig (old names renamed first; TypeError as Python
    raises it for an unknown or doubled keyword), then the table's values as
    {C name: text}, and the other arguments by name."""
    kwargs = dict(kwargs)
    for old, new in ALIASES.items():
        if old in kwargs and new in sig.parameters:
            if new in kwargs:
                raise TypeError("%s() got %s and its older name %s" % (func, new, old))
            kwargs[new] = kwargs.pop(old)
    try:
        b = sig.bind(*args, **kwargs)
    except TypeError as e:
        raise TypeError("%s(): %s" % (func, e)) from None
    values, other = {}, {}
    byname = {p.name: p for p in params}
    for k, v in b.arguments.items():
        if k in byname:
            if v is not None:
                values[byname[k].cname] = byname[k].text(v)
        else:
            other[k] = v
    return values, other
