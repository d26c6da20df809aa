"""Array type aliases shared across the packages."""

from __future__ import annotations

from typing import Any, TypeAlias

import numpy as np
from numpy.typing import NDArray

#: A float array; shapes and units are given where it is used.
Array: TypeAlias = NDArray[np.floating[Any]]
