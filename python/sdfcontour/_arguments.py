"""Checking and converting the Python functions' arguments into the core's options (one-line
ValueError / ArgumentTypeError for bad ones)."""
import numpy as _np

from . import _checks

METHODS = ("gcp", "gtcp", "mc", "mt-rt", "mt-dt")


def _bounds(bounds):
    """(lo, hi) as two float arrays of 3, from scalars or 3-sequences."""
    if bounds is None:
        bounds = (-1.0, 1.0)
    try:
        lo, hi = bounds
        lo = _np.broadcast_to(_checks.numbers_array("bounds", lo).astype(float), (3,)).copy()
        hi = _np.broadcast_to(_checks.numbers_array("bounds", hi).astype(float), (3,)).copy()
    except ValueError:
        raise ValueError("bounds must be (lo, hi), each a number or 3 numbers") from None
    limit = _checks.LARGEST_COORDINATE
    if not (_np.all(_np.abs(lo) <= limit) and _np.all(_np.abs(hi) <= limit) and _np.all(lo < hi)):
        raise ValueError(f"bounds: lo must be less than hi on every axis, all finite and at most "
                         f"{limit:g} in size")
    return lo, hi


def _brick_size(brick_size):
    if isinstance(brick_size, str):
        if brick_size != "auto":
            raise ValueError(f"brick_size must be a whole number or 'auto', got {brick_size!r}")
        return -1  # the core chooses
    if isinstance(brick_size, (int, _np.integer)) and brick_size == 0:
        return 0  # one triangulation
    try:
        return _checks.in_range("brick_size", brick_size, whole=True)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{error} (or 0 for no bricks, or 'auto')") from None


def _degree(degree):
    """The Poisson elements' degree, checked: 1 or 2."""
    if isinstance(degree, bool) or degree not in (1, 2):
        raise ValueError(f"degree must be 1 or 2, got {degree!r}")
    return int(degree)


def _poisson_options(full_depth, alpha, samples_per_node, scale, boundary, solver_tolerance,
                     finest_solver_tolerance):
    """The screened Poisson options that contour() and poisson() share, checked."""
    return dict(full_depth=_checks.in_range("full_depth", full_depth, whole=True),
                alpha=_checks.in_range("alpha", alpha),
                samples_per_node=_checks.in_range("samples_per_node", samples_per_node),
                scale=_checks.in_range("scale", scale),
                boundary=_checks.choice("boundary", boundary, ("neumann", "dirichlet", "free")),
                solver_tolerance=_checks.in_range("solver_tolerance", solver_tolerance),
                finest_solver_tolerance=_checks.in_range("finest_solver_tolerance",
                                                         finest_solver_tolerance))


def _progress(value):
    """True, False, or a callable progress(stage, done, total)."""
    if callable(value):
        return value
    if isinstance(value, (bool, _np.bool_)):
        return bool(value)
    raise _checks.ArgumentTypeError(f"progress must be True, False or a callable "
                                    f"progress(stage, done, total), got {value!r}")


def _full_depth_within(options):
    if options["full_depth"] > options["depth"]:
        raise ValueError("full_depth must be at most depth")


def _options(method, band, margin, truncation, gradient, weights, knn, fn, tie_tolerance,
             brick_size, brick_halo, depth, full_depth, alpha, samples_per_node, scale, boundary,
             solver_tolerance, progress, finest_solver_tolerance=1e-3):
    if method not in METHODS:
        raise ValueError(f"unknown method '{method}' (known: {', '.join(METHODS)})")
    auto_band = isinstance(band, str) and band == "auto"
    if isinstance(band, str) and band == "all":
        band = float("inf")
    elif auto_band:
        band = 0.0  # the core picks it from the resolution
    elif not (_checks.number("band", band) > 0 and band == band):
        raise ValueError(f"band must be a positive number of spacings (or 'all' or 'auto'), "
                         f"got {band!r}")
    if isinstance(truncation, (int, float, _np.integer, _np.floating)) and \
            not isinstance(truncation, (bool, _np.bool_)):
        if not 0 < float(truncation) < float("inf"):
            raise ValueError(f"truncation must be a positive finite number (or 'auto' or 'none'), "
                             f"got {truncation!r}")
        truncation = repr(float(truncation))  # the core reads it as the CLI's text
    if not isinstance(truncation, str):
        raise _checks.ArgumentTypeError(f"truncation must be 'auto', 'none' or a number, got "
                                        f"{truncation!r}")
    if truncation not in ("auto", "none"):
        from . import _sdfcontour  # the CLI's reading of a number ("0_1" is none)
        given = _sdfcontour.parse_number(truncation)
        if given is None or not 0 < given < float("inf"):
            raise ValueError(f"truncation must be 'auto', 'none' or a positive number as text, "
                             f"got {truncation!r}")
    o = dict(method=method, band=float(band), margin=_checks.in_range("margin", margin),
             truncation=truncation,
             gradient=_checks.choice("gradient", gradient,
                                     ("auto", "regular", "delaunay", "knn", "lattice")),
             weights=_checks.choice("weights", weights, ("james", "volume", "uniform")),
             knn=_checks.in_range("knn", knn, whole=True), fn=_checks.flag("fn", fn),
             tie_tolerance=_tie_tolerance(tie_tolerance),
             brick_size=_brick_size(brick_size),
             brick_halo=_checks.in_range("brick_halo", brick_halo),
             progress=_progress(progress) is True,  # a callable is passed on apart
             **_poisson_options(full_depth, alpha, samples_per_node, scale, boundary,
                                solver_tolerance, finest_solver_tolerance))
    if callable(progress):
        o["progress_callback"] = progress  # taken out before the options reach the core
    if isinstance(depth, str) and depth == "auto":
        o["depth_text"] = "auto"
    else:
        try:
            o["depth"] = _checks.in_range("depth", depth, whole=True)
        except (TypeError, ValueError) as error:
            raise ValueError(f"{error}, or 'auto'") from None
        _full_depth_within(o)
    return o


def _tie_tolerance(value):
    """None for "auto" (the core's: 1e-6 for the triangulation's points, 1e-3 for the
    lattice's), else the number, for both."""
    if isinstance(value, str) and value == "auto":
        return None
    try:
        return _checks.in_range("tie_tolerance", value)
    except (TypeError, ValueError) as error:
        raise type(error)(f"{error}, or 'auto'") from None


def _check_callable_arguments(resolution, batch_size):
    """Refuses a callable's resolution or batch out of range (no path makes an n^3 array)."""
    if isinstance(resolution, bool) or not isinstance(resolution, (int, _np.integer)) \
            or not 2 <= resolution <= 2048:
        raise ValueError(f"resolution must be a whole number from 2 to 2048, got {resolution!r}")
    if isinstance(batch_size, bool) or not isinstance(batch_size, (int, _np.integer)) \
            or not 1 <= batch_size <= 2**26:
        raise ValueError(f"batch_size must be a whole number from 1 to {2**26}, got "
                         f"{batch_size!r}")


def _count_or_auto(name, value, most):
    """-1 for "auto", else a whole number from 0 to `most`; ValueError otherwise."""
    if isinstance(value, str) and value == "auto":
        return -1
    if isinstance(value, (int, _np.integer)) and not isinstance(value, bool) and 0 <= value <= most:
        return int(value)
    raise ValueError(f"{name} must be a whole number from 0 to {most} or 'auto', got {value!r}")


def _split_sag(value):
    """-1 for "auto", 0 for False or "off", else spacings within the option table's range."""
    if isinstance(value, str) and value == "auto":
        return -1.0
    if value is False or (isinstance(value, str) and value == "off"):
        return 0.0
    return _checks.in_range("split_sag", value)


def _switch(name, value):
    """True, False or "auto" as the library's on/off/auto; anything else is a ValueError."""
    if isinstance(value, str) and value == "auto":
        return "auto"
    if isinstance(value, (bool, _np.bool_)):
        return "on" if value else "off"
    raise ValueError(f"{name} must be True, False or 'auto', got {value!r}")


def _lipschitz(value):
    value = float(_checks.number("lipschitz", value))
    if not 1e-6 <= value <= 1e6:
        raise ValueError(f"lipschitz must be from 1e-06 to 1e+06, got {value!r}")
    return value


def _refine_dilation(value):
    if isinstance(value, (int, _np.integer)) and not isinstance(value, (bool, _np.bool_)) \
            and 1 <= value <= 4:
        return int(value)
    raise ValueError(f"refine_dilation must be a whole number from 1 to 4 (or 'auto' for contour), "
                     f"got {value!r}")
