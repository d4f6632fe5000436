"""Statics of a linkage with an Assur plan (:mod:`.linkage_assur`), fused and vectorised.

The same member-equilibrium equations as :mod:`.linkage_forces`, K x + b = 0, solved group
by group in reverse Assur order instead of as one dense system: K is block triangular in
that order (a group's links feel only its own joints and those of later groups). Per group:

- **RRR dyad** (links a, b; pins P1, M, P2): moments of a about P1 and of b about P2 give a
  2×2 system for the middle pin's force, r1 × G = h1, r2 × G = h2 with r = M − P and
  determinant r1 × r2 (zero at the dyad's toggle); the pins' forces follow from the force
  sums;
- **RRP dyad** (rod a pinned at P1 and M, slider b on a slide along u, normal n): b's
  force sum along u gives G·u, a's moment about P1 then G·n, through r1·u (zero at the
  dyad's toggle, the rod square to the slide); the slide's normal force follows from b's
  force sum along n, its couple from b's moments;
- **crank**: its pin carries the resultant of what acts on it, the driver its moment.

What a solved group's joints exert on the bodies it hangs from is added to their known
forces. A static case needs no velocities or accelerations, and every constant load and
weight on a link folds into one resultant (:mod:`.resultant`: its force and its moment's
cos/sin parts), so the right-hand side costs a few operations per link. Poses are
processed in chunks that keep the temporaries in cache.

**The singular verdict** is that of :func:`.linkage_forces.condition`, the 2-norm condition
number of the scaled K, without its SVD where a cheap bound decides it (in
:func:`.linkage_forces.solve_linkage`): the rows of the scaled
matrix S are unit vectors, so σ_max ≤ ‖S‖_F = √m; and ‖S⁻¹‖_F is bounded block by block
from the triangular structure, each group's inverse in closed form (the RRR dyad's through
its 2×2, the RRP dyad's through r1·u). A pose whose bound is below the threshold is not
singular; only the others (near a toggle) get the exact SVD. The exact condition numbers
themselves are computed when asked for (:attr:`.linkage_forces.LinkageResults.condition`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.linkage import Joint, TorsionSpring
from mechcheck.analytic.linkage_assur import (
    AssurPlan,
    Crank,
    Dyad,
    Path,
    Placement,
    SlideDyad,
    continuous_angle,
    on_body,
    path,
    place,
    reachable,
)
from mechcheck.analytic.linkage_kinematics import (
    Array,
    LinkagePose,
    known_assembled,
    known_at_rest,
)
from mechcheck.analytic.linkage_loads import spring_axis
from mechcheck.analytic.resultant import Resultant
from mechcheck.analytic.values import GROUND, Vec2

#: Longest plan the condition bound is tried on: each group multiplies the bound by a
#: factor above 1, so for longer chains it exceeds the singular threshold whatever the pose.
BOUND_GROUPS = 24
#: Poses per chunk: ~30 live arrays of this many doubles stay within a core's L2 cache.
CHUNK = 8192


@dataclass(frozen=True)
class StaticResults:
    """What :func:`static_results` computes: the pose, every quantity (forces at every
    assembled pose, singular or not), and per pose an upper bound of the condition number."""

    pose: LinkagePose
    values: dict[str, Array]
    condition_bound: Array


def static_results(plan: AssurPlan, values: Array) -> StaticResults:
    """Statics at each driver value (N, 1): pose, reactions, efforts, springs, and the bound
    from which :func:`.linkage_forces.solve_linkage` decides the singular verdicts."""
    linkage = plan.linkage
    value = np.ascontiguousarray(values[:, 0], dtype=float)
    n = value.shape[0]
    route = path(plan, value)
    names = plan.quantity_names
    # One block, a row per quantity: one allocation, not one per column.
    out = dict(zip(names, np.empty((len(names), n)), strict=True))
    # Column-major: each coordinate is written (and read by the pose's links) as one
    # contiguous column, not strided across rows.
    q = np.empty((3 * len(linkage.moving_links), n)).T
    locked = np.empty(n)
    bound = np.full(n, np.inf)
    constants = plan.constants
    inside = np.empty(n, dtype=bool)
    for start in range(0, n, CHUNK):
        part = slice(start, min(start + CHUNK, n))
        chunk = _Chunk(plan, route, _chunk_values(value, part), constants)
        chunk.write(out, q, locked, bound, part)
        inside[part] = _finite_rows(q[part])   # while the chunk is in cache
    qdot, qddot = np.zeros(q.shape), np.zeros(q.shape)   # untouched pages cost nothing
    if not inside.all():
        qdot[~inside] = np.nan
        qddot[~inside] = np.nan
    pose = LinkagePose(linkage, np.asarray(values, dtype=float), q, qdot, qddot, locked)
    return StaticResults(known_at_rest(known_assembled(pose, inside)), out, bound)


def _finite_rows(block: Array) -> NDArray[np.bool_]:
    """Which rows of ``block`` are finite throughout: column by column (a reduction along
    rows of a few columns costs twice as much)."""
    if block.shape[0] == 1:     # one pose: one call
        return np.asarray(np.isfinite(block).all(axis=1))
    finite = np.isfinite(block[:, 0])
    for k in range(1, block.shape[1]):
        finite &= np.isfinite(block[:, k])
    return finite


def _chunk_values(value: Array, part: slice) -> Array:
    """The driver values of a chunk; a single pose's as a number (0-d), whose arithmetic
    costs a tenth of a one-element array's and rounds the same."""
    if value.shape[0] == 1:
        return value[0]
    return value[part]


class _Chunk:
    """One chunk of poses: placed, loaded, solved, bounded."""

    def __init__(self, plan: AssurPlan, route: Path, value: Array,
                 constants: dict[str, Resultant]) -> None:
        self.plan = plan
        self.linkage = plan.linkage
        self.value = value
        self.placed: Placement = place(plan, value)
        self.inside, self.locked = reachable(route, value, self.placed)
        self.angle = {link: continuous_angle(plan, route, link, value, self.placed)
                      for link in self.linkage.moving_links}
        self.constants = constants
        self.carried: dict[tuple[str, Vec2], tuple[Array | float, Array | float]] = {}

    def frame(self, link: str) -> tuple[Array | float, ...]:
        return self.placed.frames[link]

    def point(self, link: str, p0: Vec2) -> tuple[Array | float, Array | float]:
        """Where ``link`` carries its drawn point ``p0`` now: computed once per chunk (the
        output, the loads, the elimination and the bound all ask for the joints' points)."""
        key = (link, p0)
        found = self.carried.get(key)
        if found is None:
            found = self.carried[key] = on_body(self.placed.frames[link], p0)
        return found

    def write(self, out: dict[str, Array], q: Array, locked: Array, bound: Array,
              part: slice) -> None:
        linkage = self.linkage
        for name, p0 in linkage.points.items():
            x, y = self.point(self.plan.carriers[name], p0)
            out[f"x_{name}"][part] = x + linkage.offset[0]
            out[f"y_{name}"][part] = y + linkage.offset[1]
        for k, link in enumerate(linkage.moving_links):
            _, _, tx, ty = self.frame(link)
            q[part, 3 * k] = tx
            q[part, 3 * k + 1] = ty
            q[part, 3 * k + 2] = self.angle[link]
            out[f"phi_{link}"][part] = self.angle[link]
        for joint in linkage.joints:
            out[f"q_{joint.name}"][part] = self._coordinate(joint)
        springs = self.spring_forces()
        for name, s in springs.items():
            out[f"S_{name}"][part] = s
        forces = self.eliminate(self.known(springs))
        for name, f in forces.items():
            out[name][part] = f
        locked[part] = self.locked
        bound[part] = self.condition_bound()
        nan = np.atleast_1d(~self.inside)
        if nan.any():   # a pose the path does not reach has no pose and no forces
            q[part][nan] = np.nan
            for name in out:
                if not name.startswith(("x_", "y_")) or self.plan.carriers[name[2:]] != GROUND:
                    out[name][part][nan] = np.nan

    def _phi(self, link: str) -> Array | float:
        return 0.0 if link == GROUND else self.angle[link]

    def _coordinate(self, joint: Joint) -> Array | float:
        """q of a joint: the relative angle, or a slide's travel along its axis (the
        kind's :meth:`~.JointKind.coordinate`: links[1]'s translation less links[0]'s, both
        turned alike)."""
        i, j = joint.links
        if joint.kind.rotates:
            return self._phi(j) - self._phi(i)
        assert joint.axis is not None
        ci, si, ti_x, ti_y = self.frame(i)
        _, _, tj_x, tj_y = self.frame(j)
        ux = ci * joint.axis[0] - si * joint.axis[1]
        uy = si * joint.axis[0] + ci * joint.axis[1]
        return (tj_x - ti_x) * ux + (tj_y - ti_y) * uy

    # -- known forces ---------------------------------------------------------------------
    def spring_forces(self) -> dict[str, Array]:
        out = {}
        for spring in self.linkage.springs:
            if isinstance(spring, TorsionSpring):
                i, j = self.linkage.joint(spring.joint).links
                stretch = self._phi(j) - self._phi(i) - spring.free_rotation
                out[spring.name] = spring.stiffness * stretch + 0.0 * self.value
                continue
            (la, pa), (lb, pb) = spring.ends
            ax, ay = self.point(la, pa)
            bx, by = self.point(lb, pb)
            length = np.hypot(bx - ax, by - ay)
            out[spring.name] = spring.stiffness * (length - spring.free_length)
        return out

    def known(self, springs: dict[str, Array]) -> dict[str, list[Array | float]]:
        """b per moving link: [Fx, Fy, M about the origin], every known force."""
        b: dict[str, list[Array | float]] = {}
        for link in self.linkage.moving_links:
            c, s, tx, ty = self.frame(link)
            fx, fy, moment = self.constants[link].wrench((c, s))
            b[link] = [fx, fy, moment + tx * fy - ty * fx]   # about the global origin
        for spring in self.linkage.springs:
            tension = springs[spring.name]
            if isinstance(spring, TorsionSpring):
                i, j = self.linkage.joint(spring.joint).links
                _add(b, j, 0.0, 0.0, 0.0, 0.0, -tension)
                _add(b, i, 0.0, 0.0, 0.0, 0.0, tension)
                continue
            (la, pa), (lb, pb) = spring.ends
            ax, ay = self.point(la, pa)
            bx, by = self.point(lb, pb)
            d = np.stack(np.broadcast_arrays(bx - ax, by - ay), axis=-1).reshape(-1, 2)
            unit = spring_axis(self.linkage, d)[1]
            fx, fy = tension * unit[:, 0], tension * unit[:, 1]
            _add(b, la, fx, fy, ax, ay)   # tension pulls a toward b
            _add(b, lb, -fx, -fy, bx, by)
        return b

    # -- elimination ----------------------------------------------------------------------
    def eliminate(self, b: dict[str, list[Array | float]]) -> dict[str, Array | float]:
        """Every joint's reaction and driver's effort, groups in reverse Assur order."""
        out: dict[str, Array | float] = {}
        for index in range(len(self.plan.groups) - 1, -1, -1):
            group = self.plan.groups[index]
            if isinstance(group, Crank):
                self._crank(group, b, out)
            elif isinstance(group, SlideDyad):
                self._slide_dyad(index, group, b, out)
            else:
                self._dyad(index, group, b, out)
        return out

    def _crank(self, group: Crank, b: dict[str, list[Array | float]],
               out: dict[str, Array | float]) -> None:
        fx, fy, m = b[group.link]
        px, py = self.point(group.link, group.point)
        couple = px * fy - py * fx - m      # the driver's couple on the crank
        sense = 1.0 if group.joint.links[1] == group.link else -1.0
        name = group.joint.name
        out[f"F_{name}_x"], out[f"F_{name}_y"] = _signed(-sense, fx), _signed(-sense, fy)
        out[f"Q_{name}"] = _signed(sense, couple)
        _add(b, group.body, fx, fy, px, py, -couple)

    def _dyad(self, index: int, group: Dyad, b: dict[str, list[Array | float]],
              out: dict[str, Array | float]) -> None:
        x1, y1, mx, my, x2, y2 = self.placed.points[index]
        a, c = group.links
        fax, fay, ma = b[a]
        fbx, fby, mb = b[c]
        h1 = x1 * fay - y1 * fax - ma
        h2 = mb - (x2 * fby - y2 * fbx)
        r1x, r1y, r2x, r2y = mx - x1, my - y1, mx - x2, my - y2
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / (r1x * r2y - r1y * r2x)
        gx = (h1 * r2x - r1x * h2) * inv   # the middle pin's force on a
        gy = (r2y * h1 - r1y * h2) * inv
        g1x, g1y = -gx - fax, -gy - fay     # the pin at P1 on a
        g2x, g2y = gx - fbx, gy - fby       # the pin at P2 on b
        for joint, link, fx, fy in ((group.joints[0], a, g1x, g1y), (group.joints[1], a, gx, gy),
                                    (group.joints[2], c, g2x, g2y)):
            sense = 1.0 if joint.links[1] == link else -1.0
            out[f"F_{joint.name}_x"], out[f"F_{joint.name}_y"] = _signed(sense, fx), _signed(sense, fy)
        _add(b, group.bodies[0], -g1x, -g1y, x1, y1)
        _add(b, group.bodies[1], -g2x, -g2y, x2, y2)

    def _slide_dyad(self, index: int, group: SlideDyad, b: dict[str, list[Array | float]],
                    out: dict[str, Array | float]) -> None:
        x1, y1, mx, my, ux, uy = self.placed.points[index]
        a, c = group.links
        fax, fay, ma = b[a]
        fbx, fby, mb = b[c]
        h1 = x1 * fay - y1 * fax - ma
        r1x, r1y = mx - x1, my - y1
        along = fbx * ux + fby * uy          # G·u: the slide takes no force along u
        with np.errstate(divide="ignore", invalid="ignore"):
            normal = (h1 - along * (r1x * uy - r1y * ux)) / (r1x * ux + r1y * uy)   # G·n
        gx = along * ux - normal * uy       # the middle pin's force on a (n = u turned +90°)
        gy = along * uy + normal * ux
        g1x, g1y = -gx - fax, -gy - fay     # the pin at P1 on a
        slide = group.joints[2]
        sx, sy = self.point(slide.links[1], self.linkage.points[slide.at])
        push = normal + fbx * uy - fby * ux     # the slide's force on b along n
        couple = mx * gy - my * gx - mb - push * (sx * ux + sy * uy)   # and its couple
        for joint, fx, fy in ((group.joints[0], g1x, g1y), (group.joints[1], gx, gy)):
            sense = 1.0 if joint.links[1] == a else -1.0
            out[f"F_{joint.name}_x"], out[f"F_{joint.name}_y"] = _signed(sense, fx), _signed(sense, fy)
        sense = 1.0 if slide.links[1] == c else -1.0    # reported: by links[0] on links[1]
        out[f"F_{slide.name}_x"] = _signed(-sense, push * uy)
        out[f"F_{slide.name}_y"] = _signed(sense, push * ux)
        out[f"M_{slide.name}"] = _signed(sense, couple)
        _add(b, group.bodies[0], -g1x, -g1y, x1, y1)
        _add(b, group.bodies[1], push * uy, -push * ux, sx, sy, -couple)

    # -- the condition bound --------------------------------------------------------------
    def condition_bound(self) -> Array:
        """An upper bound of :func:`.linkage_forces.condition` (see the module); infinite for
        a plan of more than :data:`BOUND_GROUPS` groups, whose bound compounds group by group
        far past the threshold (the exact number is then computed, sparse)."""
        if len(self.plan.groups) > BOUND_GROUPS:
            return np.full(self.value.shape, np.inf)
        with np.errstate(over="ignore", invalid="ignore"):
            return self._condition_bound()

    def _row_norms(self) -> tuple[dict[str, float], dict[str, Array | float]]:
        """Squared norms of each link's rows in the scaled matrix (its force rows' mean, its
        moment row), or bounds of them: a pin adds 1 to each force row, a slide's normal
        force at most that; a pin adds |point|²/size² to the moment row, a slide at most
        that for its force and 1 for its couple."""
        linkage = self.linkage
        size = linkage.scale
        joints_on = self.plan.joints_on
        radius = {}     # |joint point|² / size²
        for j in linkage.joints:
            x, y = self.point(j.links[1], linkage.points[j.at])
            radius[j.name] = (x * x + y * y) / size**2
        force_row = {link: float(len(js)) for link, js in joints_on.items()}
        moment_row = {link: sum(radius[j.name] for j in js) + self.plan.couples[link]
                      for link, js in joints_on.items()}
        for link, slides in self.plan.slides_on.items():
            moment_row[link] = moment_row[link] + slides
        return force_row, moment_row

    def _condition_bound(self) -> Array:
        linkage = self.linkage
        size = linkage.scale
        force_row, moment_row = self._row_norms()
        groups = self.plan.groups
        inverse = [self._group_inverse(g, force_row, moment_row, size) for g in groups]
        links = [{g.link} if isinstance(g, Crank) else set(g.links) for g in groups]
        hung = [[g.body] if isinstance(g, Crank) else list(g.bodies) for g in groups]
        total = 0.0 * self.value
        for h in range(len(groups)):
            column: dict[int, Array] = {h: inverse[h]}
            for g in range(h - 1, -1, -1):
                acc = 0.0 * self.value
                for k in range(g + 1, h + 1):
                    touched = sum(1 for body in hung[k] if body in links[g])
                    if touched and k in column:
                        acc = acc + math.sqrt(3.0 * touched) * column[k]
                column[g] = inverse[g] * acc
            total = total + sum(x * x for x in column.values())
        rows = 3 * len(linkage.moving_links)
        return np.sqrt(rows * total)

    def _group_inverse(self, group: Crank | Dyad | SlideDyad, force_row: dict[str, float],
                       moment_row: dict[str, Array | float], size: float) -> Array:
        """A bound of ‖S_gg⁻¹‖_F, the group's diagonal block of the scaled matrix."""
        if isinstance(group, Crank):
            px, py = self.point(group.link, group.point)
            f, m = force_row[group.link], moment_row[group.link]
            return np.sqrt(2.0 * f + (py * py + px * px) * f / size**2 + m)
        if isinstance(group, SlideDyad):
            return self._slide_inverse(group, force_row, moment_row, size)
        x1, y1, mx, my, x2, y2 = self.placed.points[self.plan.groups.index(group)]
        a, c = group.links
        l1, l2 = group.lengths
        with np.errstate(divide="ignore", invalid="ignore"):
            w = math.sqrt(l1 * l1 + l2 * l2) / np.abs((mx - x1) * (my - y2) - (my - y1) * (mx - x2))
        t = np.sqrt((y1 * y1 + x1 * x1) * force_row[a] + size**2 * moment_row[a]
                    + (y2 * y2 + x2 * x2) * force_row[c] + size**2 * moment_row[c])
        return math.sqrt(3.0) * w * t + math.sqrt(2.0 * (force_row[a] + force_row[c]))

    def _slide_inverse(self, group: SlideDyad, force_row: dict[str, float],
                       moment_row: dict[str, Array | float], size: float) -> Array:
        """A bound of an RRP dyad's ‖S_gg⁻¹‖_F: its inverse (the elimination of
        :meth:`_slide_dyad`) as a sum of rank-one maps, each of Frobenius norm |column|·|row|
        in the scaled unknowns (the slide's couple ÷ size) and loads (each row times its
        norm): through G·n (its row |(P1 × Fa, ma, (r1 × u) Fb·u)| / |r1·u|; its column G,
        the P1 pin, N and the couple's lever (M − S)×n), through G·u = Fb·u, −Fa into the P1
        pin, Fb·n into N and the couple, and mb into the couple."""
        x1, y1, mx, my, ux, uy = self.placed.points[self.plan.groups.index(group)]
        a, c = group.links
        slide = group.joints[2]
        sx, sy = self.point(slide.links[1], self.linkage.points[slide.at])
        r1x, r1y = mx - x1, my - y1
        turn = r1x * uy - r1y * ux
        with np.errstate(divide="ignore", invalid="ignore"):
            row = np.sqrt((x1 * x1 + y1 * y1) * force_row[a] + size**2 * moment_row[a]
                          + turn * turn * force_row[c]) / np.abs(r1x * ux + r1y * uy)
        lever = ((mx - sx) * ux + (my - sy) * uy) / size
        fb = math.sqrt(force_row[c])
        return (np.sqrt(3.0 + lever * lever) * row
                + fb * np.sqrt(2.0 + ((mx * uy - my * ux) / size)**2)
                + math.sqrt(2.0 * force_row[a])
                + fb * np.sqrt(1.0 + ((sx * ux + sy * uy) / size)**2)
                + np.sqrt(moment_row[c]))


def _signed(sense: float, value: Array | float) -> Array | float:
    """``sense · value`` for a sense of ±1: the value or its negation, the same numbers
    (rounding is symmetric in sign) without a pass over the poses for +1."""
    return value if sense > 0.0 else -value


def _add(b: dict[str, list[Array | float]], link: str, fx: Array | float, fy: Array | float,
         px: Array | float, py: Array | float, couple: Array | float = 0.0) -> None:
    """Add a force (fx, fy) at (px, py) and a couple to a moving link's known forces."""
    if link == GROUND:
        return
    row = b[link]
    row[0] = row[0] + fx
    row[1] = row[1] + fy
    row[2] = row[2] + px * fy - py * fx + couple
