# SPDX-License-Identifier: MIT
# Type stubs of the isokit package for editors (the extension is isokit._isokit).
__version__: str

class InputError(ValueError): ...

def set_num_threads(n: int) -> None: ...
def get_num_threads() -> int: ...

from . import fields as fields
from . import operators as operators
from . import skinning as skinning
from . import tracker as tracker
