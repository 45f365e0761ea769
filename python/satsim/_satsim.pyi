"""Type stubs of the native module ``satsim._satsim`` (Rust, PyO3). Use the package
``satsim`` instead: it takes paths, texts and dicts and returns friendlier objects."""

from os import PathLike
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, PathLike[str]]
_F64_1D = npt.NDArray[np.float64]
_F64_2D = npt.NDArray[np.float64]

class SatsimError(ValueError):
    """Bad input or a failed computation; the message is the ``satsim`` command line's
    (file, line or field, what is wrong). A run that failed part-way carries ``partial``."""

class NativeModel:
    """A model (contract section 1), read and checked."""

    @staticmethod
    def from_file(path: _Path) -> NativeModel: ...
    @staticmethod
    def from_toml(text: str, origin: _Path) -> NativeModel: ...
    @property
    def origin(self) -> str: ...
    @property
    def base(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def body_names(self) -> List[str]: ...
    @property
    def hinge_names(self) -> List[str]: ...
    @property
    def total_mass(self) -> float: ...
    def dynamics_file(
        self, path: _Path
    ) -> Tuple[int, _F64_2D, _F64_1D, _F64_1D, float]: ...
    def dynamics_json(
        self, text: str, origin: _Path
    ) -> Tuple[int, _F64_2D, _F64_1D, _F64_1D, float]: ...

def run_file(path: _Path, out: Optional[_Path] = None) -> Tuple[List[str], _F64_2D]: ...
def run_text(
    text: str, origin: _Path, out: Optional[_Path] = None
) -> Tuple[List[str], _F64_2D]: ...
def campaign(
    origin: _Path,
    text: Optional[str] = None,
    threads: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
) -> Tuple[List[str], _F64_2D, List[str], List[str]]: ...
def linearize(origin: _Path, text: Optional[str] = None) -> Dict[str, Any]: ...
def modes(origin: _Path, text: Optional[str] = None) -> Dict[str, Any]: ...
