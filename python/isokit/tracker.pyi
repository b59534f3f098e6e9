# SPDX-License-Identifier: MIT
# Type stubs of isokit.tracker for editors.
from typing import Any, Callable, Dict, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from .fields import Field

_PyField = Callable[[npt.NDArray[np.float32]], Tuple[npt.ArrayLike, ...]]
_AnyField = Union[Field, _PyField]

def sample_iso_values(field: _AnyField, positions: npt.ArrayLike) -> npt.NDArray[np.float32]: ...

class Tracker:
    def __init__(self, rest: npt.ArrayLike, triangles: npt.ArrayLike, iso: npt.ArrayLike, **options: Any) -> None: ...
    def track(
        self,
        field: _AnyField,
        positions: npt.ArrayLike,
        rotations: Optional[npt.ArrayLike] = None,
        mask: Optional[npt.ArrayLike] = None,
        anchors: Optional[npt.ArrayLike] = None,
        stiffness: Optional[npt.ArrayLike] = None,
    ) -> Tuple[npt.NDArray[np.float32], Dict[str, Any]]: ...
    @property
    def flags(self) -> Dict[str, npt.NDArray[Any]]: ...
