"""The warnings that sdfcontour's functions give (re-exported by the package)."""


class FallbackWarning(UserWarning):
    """GCP could not trust the values as distances and returned marching cubes' mesh
    (``stats["fallback"]`` says why; ``strict=True`` makes it an error)."""


class RescaleWarning(UserWarning):
    """The values changed by m per unit length near the surface, not 1, and were divided by m
    (``stats["value_scale"]``)."""


class LipschitzWarning(UserWarning):
    """A callable SDF changed faster than its ``lipschitz`` bound said: it was sampled again with
    a larger bound (without it, small parts could be skipped)."""


class DroppedSamplesWarning(UserWarning):
    """Scattered samples were dropped as isolated strays (``stats["isolated_samples"]``)."""


# Shown as the package's own (sdfcontour.FallbackWarning), where they are exported.
for _warning in (FallbackWarning, RescaleWarning, LipschitzWarning, DroppedSamplesWarning):
    _warning.__module__ = "sdfcontour"
