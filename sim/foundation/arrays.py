"""The array type every floor passes around: NumPy float64 arrays (positions, speeds,
readings), named once so signatures say what they hold."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
