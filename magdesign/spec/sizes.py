"""The memory and time a spec's sizes ask for: one estimate, checked before the work.

A spec's sizes (its load points, sensors, quadrature points per chip, soft cells; a sweep's
points) set the element counts of the main arrays a run holds: the field samples of a
simulation (load points x sensors x quadrature points x 3 components), the dense
interaction matrix of the soft cells ((3 x cells)^2), the records of a sweep. A run holds
several copies of them at once (the model's values, the tangents the design solver
differentiates them with, the intermediates of the field functions), so :func:`check_fits`
estimates the bytes as elements x 8 (float64) x :data:`WORK_FACTOR` and refuses a size
whose estimate exceeds the memory available on this machine (``MemAvailable`` of
/proc/meminfo, else the physical memory). A size that fits but is large warns
(:class:`SizeWarning`) with a rough time.
"""

import os
import warnings

from magdesign.units import SpecError

# Copies of the main arrays a differentiated run holds at once (an upper estimate; a plain
# simulation holds fewer).
WORK_FACTOR = 32
# Above this many elements a run is long: a warning with a rough time, at ROUGH_RATE elements
# per second (the order of the field functions' throughput on one CPU core, float64).
SLOW_ELEMENTS = 1e8
ROUGH_RATE = 1e7


class SizeWarning(UserWarning):
    """A size that fits in memory but makes a long run."""


def available_bytes() -> int | None:
    """The memory available to a new run here (bytes): /proc/meminfo's MemAvailable, else
    the physical memory; None where neither can be read."""
    try:
        with open("/proc/meminfo") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def check_fits(
    key: str,
    elements: float,
    *,
    factor: float = WORK_FACTOR,
    what: str = "its arrays",
    slow: tuple[float, str] | None = None,
) -> None:
    """SpecError naming ``key`` (the size as written, "load.points = 100000000") when
    ``elements`` float64 values times ``factor`` exceed this machine's available memory
    (:func:`available_bytes`); a :class:`SizeWarning` above :data:`SLOW_ELEMENTS` with a
    rough time, or above ``slow``'s count of elements with its words ("each point is a
    solve"). ``what``: what the elements are, for the message."""
    need = float(elements) * 8.0 * factor
    available = available_bytes()
    if available is not None and need > available:
        raise SpecError(
            f"{key}: {what} take about {need / 1e9:.3g} GB ({float(elements):.3g} values x 8 bytes x {factor:g} "
            f"working copies), more than the {available / 1e9:.3g} GB of memory available here; expected a "
            "smaller size"
        )
    limit, why = slow or (SLOW_ELEMENTS, f"roughly {float(elements) / ROUGH_RATE:.3g} s or more")
    if elements > limit:
        message = f"{key}: {what} hold about {float(elements):.3g} values; expect a long run ({why})"
        warnings.warn(message, SizeWarning, stacklevel=2)
