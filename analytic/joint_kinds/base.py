"""What every kind of joint supplies, so that the engine never asks which kind it holds
(after sympy.physics.mechanics' ``Joint``: the equation generators read the joint, never
its type).

A kind is a value: one instance per kind, shared by every joint of that kind. It says how
many relative freedoms the joint leaves (its Sᵢ in Gruebler–Kutzbach), writes its
constraint rows and their J̇·q̇ terms, its reaction unknowns in the member-equilibrium
matrix and how they are reported, the row a driver on it adds and the effort that driver
exerts, and its Coulomb and viscous friction.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from mechcheck.analytic.rigid import Array, Constraints, ForceLayout, Motion
from mechcheck.analytic.values import length_text

if TYPE_CHECKING:
    from mechcheck.analytic.joint_kinds.drawing import JointDrawing, Placement
    from mechcheck.analytic.linalg import Batched
    from mechcheck.analytic.linkage import Joint, JointFriction, Link
    from mechcheck.analytic.linkage_kinematics import LinkagePose
    from mechcheck.analytic.motion_rows import RowPlan


@dataclass(frozen=True)
class JointFrame:
    """A joint's point now (N, 2) and, for a joint with an axis, its axis u and normal n."""

    point: Array
    u: Array | None
    n: Array | None


class JointKind(ABC):
    """One kind of joint. Subclasses fill in the class attributes and the methods."""

    #: The name a case file gives it (``kind = "revolute"``).
    name: ClassVar[str]
    #: Its letter in the seed's mobility tables (R, P, Cs, G).
    symbol: ClassVar[str]
    #: Relative freedoms it leaves between its two links (Sᵢ); it removes 3 − Sᵢ.
    freedoms: ClassVar[int]
    #: Its coordinate (and a driver on it) is an angle, else a length.
    rotates: ClassVar[bool]
    #: It joins its links at a point both carry (a pin): the friction circle, torsion
    #: springs and points shared by several links go with it.
    pins: ClassVar[bool]
    #: A driver may prescribe its coordinate.
    drivable: ClassVar[bool] = True
    #: It takes Coulomb and viscous friction (``joint_mu``, ``viscous``).
    frictional: ClassVar[bool] = True
    #: Its point ``at`` moves along a line fixed in links[0] (a slide): in a sketch
    #: (:mod:`..sketch`) that line is kept where it is drawn, and ``at`` moves along it.
    slides: ClassVar[bool] = False
    #: A sketch may hold it (:mod:`..sketch`): a gear mesh may not, since its centre
    #: distance is fixed by its pitch radii, across two links, which no dimension spans.
    sketchable: ClassVar[bool] = True

    # -- as a value ---------------------------------------------------------------------
    def __eq__(self, other: object) -> bool:
        """Equal to itself, and to its name (the case file's spelling)."""
        if isinstance(other, JointKind):
            return other.name == self.name
        return isinstance(other, str) and other == self.name

    def __hash__(self) -> int:
        return hash(self.name)

    def __repr__(self) -> str:
        return repr(self.name)

    def __str__(self) -> str:
        return self.name

    def __reduce__(self) -> tuple[object, tuple[str]]:
        from mechcheck.analytic.joint_kinds import kind_named

        return kind_named, (self.name,)

    # -- derived facts ------------------------------------------------------------------
    @property
    def rows(self) -> int:
        """Constraint rows it adds, and reaction unknowns it brings."""
        return 3 - self.freedoms

    @property
    def driver_key(self) -> str:
        """The case-file key of a driver on it."""
        return "rotation" if self.rotates else "displacement"

    @property
    def coordinate_unit(self) -> str:
        """The table unit of its coordinate q_<joint>."""
        return "deg" if self.rotates else "m"

    @property
    def effort_unit(self) -> str:
        """The table unit of a driver's effort Q_<joint> on it."""
        return "N*m" if self.rotates else "N"

    def length(self, size: float) -> float:
        """What one unit of its coordinate is worth as a length, for a linkage of ``size``
        (m): the size for an angle, 1 for a length (equations solved in lengths)."""
        return size if self.rotates else 1.0

    def describe(self, value: float, length_unit: str = "m") -> str:
        """A value of its coordinate (SI) as a message quotes it: degrees, or a length in
        ``length_unit`` (the case file's)."""
        if self.rotates:
            return f"rotation {math.degrees(value):.6g}°"
        return f"displacement {length_text(value, length_unit)}"

    # -- the case file ------------------------------------------------------------------
    @abstractmethod
    def checked(self, joint: Joint, links: Mapping[str, Link], key: str) -> Joint:
        """The joint as the engine holds it (e.g. its axis made a unit vector), or a
        :class:`~mechcheck.analytic.values.CaseError` naming ``key``'s field at fault.
        ``links`` are the linkage's links by name (the joint's own are known to exist)."""

    def check_drawing(self, joint: Joint, points: Mapping[str, tuple[float, float]],
                      key: str) -> None:
        """A CaseError if the drawn points contradict the joint (a gear pair whose centres
        are not a pitch-circle sum apart); most kinds have nothing to check."""
        return None

    # -- kinematics ---------------------------------------------------------------------
    @abstractmethod
    def constrain(self, c: Constraints, joint: Joint, row: int) -> None:
        """Write its :attr:`rows` rows of Φ and J, starting at ``row``."""

    @abstractmethod
    def accelerate(self, m: Motion, joint: Joint, out: Array, row: int) -> None:
        """Write the J̇·q̇ terms of its rows into ``out`` (N, m), starting at ``row``."""

    @abstractmethod
    def row_lengths(self, size: float) -> tuple[float, ...]:
        """Per constraint row, the length that makes it a row in metres (an angle row × size)."""

    @abstractmethod
    def drive(self, c: Constraints, joint: Joint, row: int) -> None:
        """Write the row of a driver on it (its coordinate), without the target."""

    @abstractmethod
    def drive_acceleration(self, m: Motion, joint: Joint) -> Array | None:
        """J̇·q̇ of a driver's row on it (None: zero)."""

    def plan(self, rows: RowPlan, joint: Joint, row: int) -> None:
        """Declare the rows :meth:`constrain` writes as the primitives it writes them with
        (``rows.coincide``, ``rows.angle_lock``, ``rows.along``), so that they are evaluated
        over all the joints at once (:mod:`..motion_rows`); by default the kind's own
        :meth:`constrain` and :meth:`accelerate` write them, one joint at a time."""
        rows.by_the_joint(joint, row)

    def plan_drive(self, rows: RowPlan, joint: Joint, row: int) -> None:
        """:meth:`plan` for the row of a driver on it (:meth:`drive`)."""
        rows.by_the_joint(joint, row, drive=True)

    @abstractmethod
    def coordinate(self, pose: LinkagePose, joint: Joint) -> tuple[Array, Array, Array]:
        """q, q̇, q̈ of the joint at each pose."""

    def value(self, pose: LinkagePose, joint: Joint) -> Array:
        """q alone, the same numbers as :meth:`coordinate`'s (a kind may spare the rates)."""
        return self.coordinate(pose, joint)[0]

    # -- statics --------------------------------------------------------------------------
    @abstractmethod
    def frame(self, pose: LinkagePose, joint: Joint) -> JointFrame:
        """Where it acts now."""

    @abstractmethod
    def react(self, k: Batched, layout: ForceLayout, joint: Joint, frame: JointFrame) -> None:
        """Its reaction unknowns' columns of K (by links[0] on links[1], reversed on links[0])."""

    def react_all(self, k: Batched, layout: ForceLayout, joints: Sequence[Joint],
                  frames: Sequence[JointFrame]) -> None:
        """:meth:`react` of each of the linkage's joints of this kind, in order (a kind may
        compute them together: one pose pays each array operation's fixed cost)."""
        for joint, frame in zip(joints, frames, strict=True):
            self.react(k, layout, joint, frame)

    @abstractmethod
    def reaction_lengths(self, size: float) -> tuple[float, ...]:
        """Per reaction unknown, the length that makes it a force (a couple × 1/size …):
        what the condition number scales its column by."""

    @abstractmethod
    def exert(self, k: Batched, layout: ForceLayout, col: int, joint: Joint,
              frame: JointFrame) -> None:
        """The column of a driver's effort on it."""

    @abstractmethod
    def quantities(self, joint: Joint) -> dict[str, str]:
        """The reaction quantities it reports, with their table units."""

    @abstractmethod
    def reported(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        """Its reported reactions from its unknowns x (N, rows) and the friction force
        along its axis (N,) (zero for a pin)."""

    # -- drawing --------------------------------------------------------------------------
    @abstractmethod
    def drawing(self, joint: Joint, place: Placement) -> JointDrawing:
        """What a drawing of the linkage at the pose ``place`` shows of the joint, and where
        its reaction acts (:mod:`.drawing`)."""

    # -- friction -------------------------------------------------------------------------
    def nonlinear_coefficient(self, joint: Joint) -> float:
        """The coefficient of a reaction part that follows the size of its unknowns whatever
        the friction (a gear's radial part, tan α); 0: none. Applied by :meth:`coulomb`."""
        return 0.0

    @abstractmethod
    def coulomb_coefficient(self, friction: JointFriction, joint: Joint) -> float:
        """μ·r (a pin with a radius) or μ (a slide); 0 without Coulomb friction."""

    @abstractmethod
    def coulomb(self, pose: LinkagePose, layout: ForceLayout, joint: Joint, coefficient: float,
                sense: Array, x: Array, phi: Array, dphi: Batched) -> None:
        """Add its Coulomb load −coefficient·sense·|reaction| to φ (N, 3n) and its
        derivative to the entries of ∂φ/∂x (3n × columns), from all the unknowns x."""

    @abstractmethod
    def sliding_friction(self, coefficient: float, sense: Array, x: Array) -> Array:
        """The Coulomb force along its axis (N,) from its own unknowns x (N, rows): part of
        its reported force; zero where friction is a moment (a pin)."""

    @abstractmethod
    def viscous(self, b: Array, layout: ForceLayout, pose: LinkagePose, joint: Joint,
                c: float) -> None:
        """Add its viscous load −c·q̇ (on links[1], reversed on links[0]) to b."""
