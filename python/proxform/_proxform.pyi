"""Type stubs of the extension module (crates/proxform-py). Units: SI and radians; world
frame x forward, y left, z up; UAVs numbered from 1."""

from typing import Any, Callable, Optional, Sequence, Union, final

import numpy as np
import numpy.typing as npt

__version__: str

class ScenarioError(ValueError):
    """A scenario or comparison that could not be loaded."""

    key: Optional[str]
    line: Optional[int]
    source: str

@final
class Scenario:
    @staticmethod
    def from_toml(text: str, source: str = "<string>") -> Scenario: ...
    @staticmethod
    def from_dict(d: dict[str, Any], source: str = "<dict>") -> Scenario: ...
    @staticmethod
    def builtin(name: str, uavs: Optional[int] = None) -> Scenario: ...
    def with_values(self, changes: dict[str, Any]) -> Scenario: ...
    def to_toml(self) -> str: ...
    def resolved(self) -> dict[str, Any]: ...
    @property
    def name(self) -> str: ...
    @property
    def uavs(self) -> int: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def navigator(self) -> int: ...
    @property
    def safety_distance_m(self) -> float: ...
    def initial_states(self) -> npt.NDArray[np.float64]: ...
    def navigator_state(self, t_s: float) -> npt.NDArray[np.float64]: ...
    def allowable_errors(self) -> npt.NDArray[np.float64]: ...
    def formation_errors(self, states: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]: ...
    # The resolved top-level keys (a slot at runtime, listed in tests/stubtest-allowlist.txt).
    def __getattr__(self, name: str) -> Any: ...

@final
class Decision:
    @property
    def outcome(self) -> str: ...
    @property
    def input(self) -> list[float]: ...
    @property
    def normalised_sq(self) -> Optional[float]: ...
    @property
    def occupied_areas(self) -> int: ...
    @property
    def main_refs(self) -> int: ...
    @property
    def isolated(self) -> int: ...
    @property
    def own_suspect(self) -> bool: ...
    @property
    def setpoint(self) -> Optional[list[float]]: ...

_Neighbours = Union[npt.ArrayLike, Sequence[tuple[int, Sequence[float]]]]

@final
class Controller:
    def __new__(cls, scenario: Scenario, uav: int) -> Controller: ...
    def step(
        self,
        t_s: float,
        own: npt.ArrayLike,
        neighbours: _Neighbours,
        ages: Optional[Sequence[float]] = None,
        radio: Optional[Sequence[bool]] = None,
    ) -> Decision: ...
    def propagate(self, state: Sequence[float], input: Sequence[float]) -> npt.NDArray[np.float64]: ...
    @property
    def uav(self) -> int: ...

@final
class Controllers:
    outcomes: tuple[str, str, str]
    def __new__(cls, scenario: Scenario, uavs: Optional[Sequence[int]] = None) -> Controllers: ...
    @property
    def uavs(self) -> list[int]: ...
    def step(
        self,
        t_s: float,
        own: npt.ArrayLike,
        counts: npt.ArrayLike,
        ids: npt.ArrayLike,
        states: npt.ArrayLike,
        ages: Optional[npt.ArrayLike] = None,
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int8]]: ...

def builtin_names() -> list[str]: ...
def run(
    scenario: Scenario,
    seed: int = 1,
    runs: int = 1,
    threads: int = 0,
    trajectories: bool = True,
    adjust: bool = True,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> tuple[str, dict[str, Any], Optional[dict[str, Any]]]: ...
def compare(
    text: Optional[str],
    source: str,
    read_text: Callable[[str], str],
    seeds: Optional[int] = None,
    duration_s: Optional[float] = None,
    threads: int = 0,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> tuple[dict[str, Any], dict[str, Any]]: ...
