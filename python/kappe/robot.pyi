from typing import Any, Optional

import numpy as np

from . import Result

def ik(pose: Any, flange_from_tcp: Optional[Any] = ...) -> np.ndarray: ...
def plan(design: Any = ..., **kwargs: Any) -> Result: ...
