"""Delamination and friction state update after each converged load step, MODEL.md §9-§10.

Per step (thesis (4.22)-(4.85), with the re-equilibration the spec recommends):
  1. Newton at the new load level with penalty contact (consistent tangent) and the friction
     loads of the last converged state (explicit, as in the thesis);
  2. ``update``: g_T^max ← max(g_T^max, |g_T|) at released points; the failure function V at
     bonded points; failed points release their nearest node at this interface, in every
     element sharing it (irreversible); the bond matrix is rebuilt; newly released points get
     the return-mapped shear (4.71)-(4.75) as friction load;
  3. while something new failed: solve the same load level again.
Friction (``DelaminationSettings.friction``):
  * ``"return_mapping"`` (default): a penalty stick/slip law (elastic stick with α_T, exact
    return mapping onto the slip limit) whose slip limit is the thesis's τ^Gleit_max(g_T^max, σ33)
    (4.76)-(4.78), (4.84), frozen within a step; direction and stick are implicit with a
    consistent tangent (the standard penalty-Coulomb return mapping MODEL.md §10 recommends).
    Right after fracture the stick anchor is set so that the point transmits exactly the
    return-mapped shear (4.71)-(4.75).
  * ``"explicit"`` (the thesis's treatment): |τ'| = τ^Gleit_max along the last slip direction,
    applied as external loads without stiffness, updated after every converged solution.
In both, σ33 is the contact pressure and there is no friction where the gap is open.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..cohesive import (FULL_DAMAGE, CohesiveBlock, CohesiveLaw, cohesive_traction_energy, path_dissipation,
                        separation_measures, stick_penalty)
from ..contact import ContactBlock, friction_shape_inverse
from ..delamination import InterfaceLaw, failure_function, return_map_at_fracture, tau_delam, tau_slide
from ..interfaces import Interface, interface_state, interfaces
from ..process_zone import Arm, in_plane_modulus, zone_lengths


@dataclass
class InterfaceRun:
    block: ContactBlock
    law: InterfaceLaw
    law_initial: InterfaceLaw
    initial: np.ndarray  # (e, q) points in an initially debonded zone
    gmax: np.ndarray  # (e, q) history variable g_T^max
    tau: np.ndarray  # (e, q, 3) friction load τ' (force of the upper on the lower layer per area)
    fresh: np.ndarray  # (e, q) released in the last update, still on the return-mapped load
    V: np.ndarray  # (e, q) failure function at the last update (nan where released)
    gap: np.ndarray  # (e, q)
    slip: np.ndarray  # (e, q, 3) tangential relative displacement g_T
    pressure: np.ndarray  # (e, q) contact pressure (≤ 0)
    first_failure: float | None = None


@dataclass
class CohesiveRun:
    """State of one cohesive interface (issue 13): the committed damage is ``block.d_old``;
    friction on the damaged share under compression uses the contact block's return mapping
    with a slip limit frozen per step."""

    block: CohesiveBlock
    law: CohesiveLaw
    gmax: np.ndarray  # (e, q) largest tangential separation so far (slip softening (4.76))
    delta: np.ndarray  # (e, q, 3) separation at the last commit
    t_fric: np.ndarray  # (e, q, 3) friction traction (damaged share) at the last commit
    energy: np.ndarray  # [fracture, friction, viscous] dissipated so far (energy)
    first_damage: np.ndarray  # () load factor of the first damage (nan: none yet)
    initial: np.ndarray  # (e, q) points of initially debonded zones
    # (e, q) fracture energy per area dissipated so far at each point (the ledger's energy[0]
    # point by point: Σ w·fracture = energy[0]); G_c(B) where a point debonded along a proportional
    # path, between 0 and G_c in the process zone
    fracture: np.ndarray
    first_failure: float | None = None  # first point fully debonded
    onset_B: float | None = None  # mode ratio B = G_II/G_T of the points that damaged first

    def update(self, u: np.ndarray, lam: float) -> None:
        """Commit the converged state: damage, dissipated energies, friction limit of the next step."""
        blk, cb, law = self.block, self.block.contact, self.law
        blk.set_load_factor(lam)
        delta, t, d, _ = blk.point_state(u)
        d_inv = blk.last_inviscid
        _, ds, lam_eq, B, _, _ = separation_measures(delta, cb.A3)
        w = cb.w
        d_prev = blk.dv_old if blk.dv_old is not None else blk.d_old  # acting damage of the last commit
        grow = d > d_prev
        # fracture: ∫ ½Kλ² dd along the separation path from the last commit (sub-stepped, the
        # mode ratio may turn: cohesive.path_dissipation)
        frac = path_dissipation(self.delta, delta, cb.A3, d_prev, d, blk.K, law)
        # viscous regularisation: the work of the cohesive tractions on the separation increment
        # (trapezoid, the rule of the external work) less the change of the stored energy is the
        # whole dissipation of the step; beyond the closed form of the rate-independent law it is
        # viscous. (A trapezoid of the driving force ½Kλ² over the damage increment - the earlier
        # rule - over-counted where the damage of a point grows a lot within one step: DCB on 300
        # elements, η = 1e-5: 219 against 206 for fracture, balance error -34 %.) It includes the
        # step's quadrature error, which the rate-independent ledger leaves in the balance error.
        if law.viscosity > 0:
            t0, psi0 = cohesive_traction_energy(self.delta, cb.A3, d_prev, blk.K)
            _, psi1 = cohesive_traction_energy(delta, cb.A3, d, blk.K)
            work = 0.5 * np.einsum("eqi,eqi->eq", t0 + t, delta - self.delta)
            visc = work - (psi1 - psi0) - frac
        else:
            visc = np.zeros_like(frac)
        tf = np.zeros_like(t)
        if cb.cap is not None and np.any(cb.cap > 0):
            tf, _ = cb.friction_traction(u, delta)
        tf = d[..., None] * tf
        P = cb.projector()
        dslip = np.einsum("eqij,eqj->eqi", P, delta - self.delta)
        fric = 0.5 * np.einsum("eqi,eqi->eq", self.t_fric + tf, dslip)
        self.energy = self.energy + np.array([float((w * frac).sum()), float((w * fric).sum()),
                                              float((w * visc).sum())])
        self.fracture = self.fracture + frac
        blk.d_old, blk.dv_old, blk.lam_old = d_inv, d, float(lam)
        self.delta, self.t_fric = delta, tf
        fresh = ~self.initial  # initially debonded zones do not count as new damage
        if np.isnan(self.first_damage) and np.any((d > 0) & fresh):
            self.first_damage = np.array(lam, float)
            first = (d > 0) & fresh  # the mode of the loading where damage starts (process-zone warning)
            self.onset_B = float(np.average(B[first], weights=w[first] * d[first]))
        if self.first_failure is None and np.any((d >= FULL_DAMAGE) & fresh):
            self.first_failure = lam
        # --- friction of the next step on the damaged share under compression: the thesis's
        # slip-softening limit (4.76) without its adhesive part τ_Delam(0), which the cohesive law
        # carries and softens: μ0 (τ_Delam(σ) - τ_Delam(0)) / (1 + (1/μ - 1)(g/g_T^μ)²), at least μ_C|σ|
        dn = np.einsum("eqi,eqi->eq", delta, cb.A3)
        sigma = blk.K * np.minimum(dn, 0.0)
        gabs = np.linalg.norm(ds, axis=-1)
        self.gmax = np.where(d > 0, np.maximum(self.gmax, gabs), self.gmax)
        ratio = self.gmax / law.gT_mu if np.isfinite(law.gT_mu) else 0.0 * self.gmax
        thesis_law = InterfaceLaw(law.sigma_max, law.tau_max, law.p)
        cap = law.mu0 * (tau_delam(sigma, thesis_law) - law.tau_max) / (1.0 + (1.0 / law.mu - 1.0) * ratio**2)
        cap = np.maximum(cap, law.mu_coulomb * np.abs(sigma))
        newcap = np.where((d > 0) & (dn < 0), cap, 0.0)
        # anchor: keep the committed friction traction continuous on the new limit
        tconv = np.where(d[..., None] > 0, tf / np.where(d > 0, d, 1.0)[..., None], 0.0)
        tn = np.linalg.norm(tconv, axis=-1)
        x = np.clip(tn / np.where(newcap > 0, newcap, 1.0), 0.0, 0.999)
        e = tconv / np.where(tn > 0, tn, 1.0)[..., None]
        gTu = np.einsum("eqij,eqj->eqi", P, delta)
        cb.cap = newcap
        self.set_stick_penalty()
        cb.g_p = np.where((newcap > 0)[..., None], gTu - (x * newcap)[..., None] * e / cb.alpha_T[..., None], gTu)
        cb.t_n = tconv

    def set_stick_penalty(self) -> None:
        """The friction's stick penalty per point from the block's slip limits
        (:func:`~layershell.cohesive.stick_penalty`; α_T the law's, or the cohesive penalty K):
        at construction, at each commit and after a restore."""
        cb = self.block.contact
        base = self.law.alpha_T if self.law.alpha_T is not None else self.block.K
        cb.alpha_T = stick_penalty(base, cb.cap, self.law.tau_max)


@dataclass
class DelaminationSettings:
    max_release: int | None = None  # nodes released per re-solution (largest V first)
    # re-solutions per load step at most: a cost limit, since each re-solution releases at least
    # one node, so a cascade ends by itself (the CFRP plate on 24 × 16 needed more than 130 at λ = 32)
    max_resolves: int = 1000
    friction: str = "return_mapping"  # or "explicit"
    # step cutting: a (sub)step whose re-solutions debond more than this fraction of the interface
    # area is undone and its load increment halved (at most ``max_debond_cuts`` times per step)
    max_debond_fraction: float | None = None
    max_debond_cuts: int = 4
    # False: the thesis's procedure (MODEL.md §9: evaluate once per converged step, no
    # re-equilibration): releases act from the next load step on
    reequilibrate: bool = True
    # interface tractions of the criterion: "raw" (displacement derivatives at the face Gauss
    # points, the thesis) or "recovered" (layershell.recovery: equilibrium through the thickness)
    stresses: str = "raw"


@dataclass
class InterfaceController:
    """Owns the interface states of a :class:`~layershell.solver.problem.Problem`."""

    runs: list[InterfaceRun]
    settings: DelaminationSettings = field(default_factory=DelaminationSettings)
    resolves: int = 0  # re-solutions in the current step
    lam: float = 0.0
    mesh_nodes: np.ndarray | None = None  # for plots
    new_warnings: list = field(default_factory=list)  # warnings of the last update (cohesive process zone)
    stabilized: dict | None = None  # automatic viscous stabilisation: {load_factor, viscosity} (stabilize)
    # relaxations at a fixed load past a snap-back or limit point (unstable = "relax", solver/newton.py
    # relax): one dict per event, and the runs whose viscous law a relaxation has switched on
    relaxations: list = field(default_factory=list)
    relaxing: list = field(default_factory=list, repr=False)
    # thesis-law contact moved from the face Gauss points to the nodes where its contact set found no
    # equilibrium (contact_to_nodes): one dict per move {load_factor, interfaces}
    contact_moves: list = field(default_factory=list)
    contact_moved_at: float | None = None  # the load factor of the last move (error messages)
    # re-solutions at a fixed load that only pseudo-transient settling solved (solver/newton.py
    # settle): one dict per event, reported and emptied by the runner
    settlements: list = field(default_factory=list)
    energy: np.ndarray = field(default_factory=lambda: np.zeros(2))  # [external work, bulk strain energy]
    u_last: np.ndarray | None = None  # state of the last energy update (path integrals)
    f_last: np.ndarray | None = None  # [external force, layers' internal force] there

    # ------------------------------------------------------------------ set-up
    @classmethod
    def build(cls, problem, laws: dict[int, InterfaceLaw], initial: dict[int, np.ndarray],
              initial_laws: dict[int, InterfaceLaw], settings: DelaminationSettings | None = None):
        model, dm = problem.model, problem.dm
        runs = []
        for itf in interfaces(model):
            if itf.upper not in laws or itf.elements.size == 0:
                continue
            law = laws[itf.upper]
            if isinstance(law, CohesiveLaw):
                runs.append(_cohesive_run(problem, itf, law, initial.get(itf.upper)))
                continue
            alpha = law.alpha_N if law.alpha_N is not None else _default_penalty(model, itf)
            blk = ContactBlock.build(model, dm, itf, alpha, rule=law.rule)
            blk.strength = law.sigma_max  # the scale of its set violations (solver/newton.py)
            ne, nq = blk.w.shape
            if (settings or DelaminationSettings()).friction == "return_mapping":
                blk.alpha_T = law.alpha_T if law.alpha_T is not None else _default_stick(model, itf)
                blk.cap, blk.t_n, blk.g_p = np.zeros((ne, nq)), np.zeros((ne, nq, 3)), np.zeros((ne, nq, 3))
            init_nodes = np.zeros(model.mesh.n_nodes, bool)
            if itf.upper in initial:
                init_nodes[initial[itf.upper]] = True
                problem.bonded[itf.upper] = problem.bonded[itf.upper] & ~init_nodes
            ini = init_nodes[blk.conn[:, blk.region]]
            if blk.cap is not None:  # initial zones start in contact with g_T^max = 0
                blk.cap = np.where(ini, tau_slide(0.0, 0.0, initial_laws.get(itf.upper, law)), 0.0)
            z = np.zeros((ne, nq))
            runs.append(InterfaceRun(blk, law, initial_laws.get(itf.upper, law), ini, z.copy(),
                                     np.zeros((ne, nq, 3)), np.zeros((ne, nq), bool), np.full((ne, nq), np.nan),
                                     z.copy(), np.zeros((ne, nq, 3)), z.copy()))
        ctl = cls(runs, settings or DelaminationSettings(), mesh_nodes=model.mesh.nodes)
        problem.extra_blocks = [r.block for r in runs]
        ctl.sync(problem)
        return ctl

    def sync(self, problem) -> None:
        """Released flags of the contact points from the nodal bond state; friction load vector."""
        for r in self.runs:
            if isinstance(r, CohesiveRun):
                continue
            r.block.released = ~problem.bonded[r.block.itf.upper][r.block.conn[:, r.block.region]]
        F = np.zeros(problem.dm.n_full)
        for r in self.runs:
            if isinstance(r, CohesiveRun):
                continue
            if r.block.alpha_T is None:  # explicit friction: external loads
                r.block.load_vector(r.tau * r.block.released[..., None], F)
        problem.F_friction = F

    # ------------------------------------------------------------------ per step
    def begin_step(self) -> None:
        """A load step (or path increment) was recorded: the next one starts its own count of
        re-solutions (``[delamination] max_resolves`` is per load step; before this was called,
        the count ran over the whole run, from its start or restart, and the weak-friction §5.1
        plate on 24 × 24 stopped at λ = 0.625 after 110 re-solutions spread over six steps)."""
        self.resolves = 0

    def update(self, problem, u: np.ndarray, lam: float) -> bool:
        """After a converged solution: history, failures, release, friction. True = re-solve."""
        self.lam = lam
        model, dm = problem.model, problem.dm
        new_any = False
        if any(isinstance(r, CohesiveRun) for r in self.runs):
            self._path_energies(problem, u, lam)
        for r in self.runs:
            if isinstance(r, CohesiveRun):
                started = r.onset_B is None
                r.update(u, lam)
                if started and r.onset_B is not None:  # damage started: is its process zone resolved?
                    self.new_warnings += _process_zone_warning(model, r, r.onset_B)
                continue
            blk, itf = r.block, r.block.itf
            ne, nq = blk.w.shape
            # the criterion's tractions at the face Gauss points (3.48); the contact block's point q
            # (Gauss, or on the nodal rule the node itself) represents the region of the same node
            # (contact.point_regions), so t[e, q] is its region's traction on either rule
            ps = interface_state(model, dm, u, itf, "gauss", self.settings.stresses, lam)
            t = ps.traction().reshape(ne, nq, 3)
            m = ps.m.reshape(ne, nq, 3, 3)
            rel = blk.released
            # --- slip, gap, pressure, history at released points
            du = blk.relative_displacement(u)
            n = m[..., 2, :]
            gT = du - np.einsum("eqi,eqi->eq", du, n)[..., None] * n
            g = np.einsum("eqi,eqi->eq", du, blk.A3)
            r.gap, r.slip = g, gT
            r.pressure = np.where(rel & (g < 0), blk.alpha * g, 0.0)
            gabs = np.linalg.norm(gT, axis=-1)
            r.gmax = np.where(rel & ~r.fresh, np.maximum(r.gmax, gabs), r.gmax)
            H_up = model.layers[itf.upper].thickness[blk.conn].mean(1)[:, None]
            open_gap = (r.law.open_gap if r.law.open_gap is not None else 0.1 * H_up)
            closed = g <= open_gap
            law_cap = np.where(r.initial, tau_slide(r.pressure, r.gmax, r.law_initial),
                               tau_slide(r.pressure, r.gmax, r.law))
            if blk.alpha_T is not None:
                # --- return mapping: commit the converged traction, new slip limit for the next solve
                t_conv, _ = blk.friction_traction(u)
                P = blk.projector()
                gTu = np.einsum("eqij,eqj->eqi", P, du)
                # keep the trial where it is (the anchor g_p only moves with the limit): the committed
                # traction is re-expressed on the new limit so that t stays continuous
                blk.t_n = np.where(rel[..., None], t_conv, 0.0)
                newcap = np.where(rel & closed, law_cap, 0.0)
                tn = np.linalg.norm(t_conv, axis=-1)
                ratio = np.clip(tn / np.where(newcap > 0, newcap, 1.0), 0.0, 0.999)
                x = friction_shape_inverse(ratio)  # f(x) = ratio
                e = t_conv / np.where(tn > 0, tn, 1.0)[..., None]
                blk.g_p = np.where(rel[..., None], gTu - (x * newcap)[..., None] * e / blk.alpha_T, 0.0)
                blk.cap = newcap
                r.tau = blk.t_n
            else:
                # --- explicit loads of sliding points, used in the next solution
                tiny = 1e-12 * model.mesh.size()
                has_dir = gabs > tiny
                direction = np.where(has_dir[..., None], gT / np.where(has_dir, gabs, 1.0)[..., None], 0.0)
                old = np.linalg.norm(r.tau, axis=-1)
                keep_dir = ~has_dir & (old > 0)  # no slip yet: keep the return-mapped direction
                direction = np.where(keep_dir[..., None], r.tau / np.where(old > 0, old, 1.0)[..., None], direction)
                sliding = rel & ~r.fresh
                r.tau = np.where((sliding & closed)[..., None], law_cap[..., None] * direction,
                                 np.where(sliding[..., None], 0.0, r.tau))
            r.fresh[:] = False
            # --- failure at bonded points (4.15)-(4.16)
            V, failed = failure_function(t, r.law)
            r.V = np.where(rel, np.nan, V)
            cand = failed & ~rel
            if not cand.any():
                continue
            e_i, q_i = np.nonzero(cand)
            nodes = blk.conn[e_i, blk.region[q_i]]
            score = np.where(np.isfinite(V[e_i, q_i]), V[e_i, q_i], np.inf)
            order = np.argsort(-score, kind="stable")
            uniq = list(dict.fromkeys(nodes[order].tolist()))
            if self.settings.max_release:
                uniq = uniq[: self.settings.max_release]
            problem.bonded[itf.upper][np.asarray(uniq)] = False
            if r.first_failure is None:
                r.first_failure = lam
            now = ~problem.bonded[itf.upper][blk.conn[:, blk.region]]
            new = now & ~rel
            # --- return mapping at fracture (4.71)-(4.75): shear part as friction load
            tm = return_map_at_fracture(t, r.law)
            tau_rm = tm[..., 0, None] * m[..., 0, :] + tm[..., 1, None] * m[..., 1, :]
            r.tau = np.where(new[..., None], tau_rm, r.tau)
            r.fresh = new
            if blk.alpha_T is not None:  # anchor so that the point transmits the mapped shear (×0.999)
                P = blk.projector()
                gTu = np.einsum("eqij,eqj->eqi", P, du)
                # the friction law acts in the undeformed tangent plane (P); the mapped shear is
                # expressed in the current basis m_α, so project it (keeps the tangent symmetric)
                tau_rm = np.einsum("eqij,eqj->eqi", P, tau_rm)
                x0 = friction_shape_inverse(0.999)  # f(x0) = 0.999
                blk.t_n = np.where(new[..., None], 0.999 * tau_rm, blk.t_n)
                blk.g_p = np.where(new[..., None], gTu - x0 * tau_rm / blk.alpha_T, blk.g_p)
                blk.cap = np.where(new, np.linalg.norm(tau_rm, axis=-1), blk.cap)
            new_any = True
        if new_any:
            problem.rebuild_constraints()
            self.resolves += int(self.settings.reequilibrate)
        self.sync(problem)
        if self.resolves > self.settings.max_resolves:
            from .newton import ConvergenceError

            raise ConvergenceError(
                f"more than {self.settings.max_resolves} re-solutions at load factor {lam:.6g} (the debonded "
                f"fraction of the interfaces is now {self.debonded_fraction():.3g}): the debonding does not "
                "stabilise at this load, each re-solution releasing more node regions (unstable delamination). "
                "The converged steps are kept; raise [delamination] max_resolves (re-solutions per load step) to "
                "follow the cascade to its end, or, where the whole interface is expected to debond, read this "
                "load factor as the limit of the bond", lam, float("nan"))
        return new_any and self.settings.reequilibrate

    # ------------------------------------------------------------------ contact rule
    def contact_to_nodes(self, problem, u: np.ndarray, lam: float, reason: str = "") -> bool:
        """Move the penalty contact and friction between debonded layers of every thesis-law
        interface whose rule the model file left open (``InterfaceLaw.rule_auto``) from the face
        Gauss points to the nodes (rule "lobatto") - what ``load_steps`` does where a solve at
        the Gauss points finds no equilibrium. There the stiff penalty's contact set can cycle on
        refined meshes (the §5.1 plate with weak friction on 12 × 12: at λ = 0.75 the set went
        round through 23, 21, 21, 22 and 23 points, the leaving points open by 10⁻⁸ m - a
        tension of 3.4 MPa under α_N - and the entering ones closed by 2·10⁻⁶ m), while at the
        nodes, where each point sees only its own node, it settles.

        Point q of either rule represents the region of the same node (contact.point_regions),
        so the released flags, the history of the points (g_T^max, friction loads) and the
        friction state carry over point by point; the stick anchors g_p are shifted so that each
        point keeps its trial traction α_T (P Δu - g_p) at ``u``, the state of the interfaces'
        last commit; ``reason``: why the solve failed (recorded). The stress criterion (4.15)
        stays at the Gauss points. True where something
        moved (the assembler's pattern is then rebuilt; the move is recorded in
        ``contact_moves``, which the runner reports with :func:`contact_move_message`)."""
        moved = []
        for r in self.movable_contact():
            old = r.block
            new = self._set_rule(problem, r, "lobatto")
            if old.alpha_T is not None:
                gT_old = np.einsum("eqij,eqj->eqi", old.projector(), old.relative_displacement(u))
                gT_new = np.einsum("eqij,eqj->eqi", new.projector(), new.relative_displacement(u))
                new.g_p = np.where(new.released[..., None], gT_new - (gT_old - old.g_p), new.g_p)
            moved.append(problem.model.layers[old.itf.upper].name)
        if not moved:
            return False
        problem.assembler.add_blocks(problem.extra_blocks)
        self.sync(problem)
        self.contact_moves.append({"load_factor": float(lam), "interfaces": moved, "reason": reason})
        self.contact_moved_at = float(lam)
        return True

    def movable_contact(self) -> list[InterfaceRun]:
        """The thesis-law runs whose contact :meth:`contact_to_nodes` would move: at the face
        Gauss points, with the rule left open in the model file (``InterfaceLaw.rule_auto``)."""
        return [r for r in self.runs if isinstance(r, InterfaceRun) and r.law.rule == "gauss" and r.law.rule_auto]

    def _set_rule(self, problem, r: InterfaceRun, rule: str) -> ContactBlock:
        """Rebuild the contact block of the thesis-law run ``r`` on the face points of ``rule``,
        with the released flags, the penalties and the friction state (slip limit, committed
        traction, anchor) of the old block point by point; ``problem.extra_blocks`` then holds
        it (the caller rebuilds the assembler's pattern)."""
        old = r.block
        new = ContactBlock.build(problem.model, problem.dm, old.itf, old.alpha, rule=rule)
        new.released, new.strength = old.released.copy(), old.strength
        if old.alpha_T is not None:
            new.alpha_T = old.alpha_T
            new.cap, new.t_n, new.g_p = old.cap.copy(), old.t_n.copy(), old.g_p.copy()
        r.block, r.law, r.law_initial = new, replace(r.law, rule=rule), replace(r.law_initial, rule=rule)
        problem.extra_blocks = [q.block for q in self.runs]
        return new

    # ------------------------------------------------------------------ restart
    #: the friction state of a contact block (the history of an :class:`InterfaceRun` is every
    #: array field of it: initial, gmax, tau, fresh, V, gap, slip, pressure)
    BLOCK_ARRAYS = ("cap", "t_n", "g_p")

    @staticmethod
    def _run_arrays(r: InterfaceRun) -> list[str]:
        return [f.name for f in fields(r) if isinstance(getattr(r, f.name), np.ndarray)]

    def state(self, problem) -> dict[str, np.ndarray]:
        """Copies of everything that the next load steps depend on, as flat named arrays (for
        :mod:`layershell.checkpoint`): the nodal bond flags of every interface, and per interface
        the history (g_T^max, slip, gap, pressure, friction loads, failure function, freshly
        released points, first failure) and the return-mapping state (slip limit, committed
        traction, slip anchor). The released points and the friction load vector follow from
        these (:meth:`sync`)."""
        out: dict[str, np.ndarray] = {f"bonded.{k}": np.array(v, copy=True) for k, v in problem.bonded.items()}
        out["lam"] = np.array(self.lam, float)
        for i, r in enumerate(self.runs):
            for name in self._run_arrays(r):
                out[f"run{i}.{name}"] = np.array(getattr(r, name), copy=True)
            out[f"run{i}.first_failure"] = np.array(np.nan if r.first_failure is None else r.first_failure, float)
            for name in self.BLOCK_ARRAYS:
                value = getattr(_kin(r.block), name)
                if value is not None:
                    out[f"run{i}.block.{name}"] = np.array(value, copy=True)
            if isinstance(r, InterfaceRun):  # the contact's face points (contact_to_nodes may have moved them)
                out[f"run{i}.nodal_contact"] = np.array(r.law.rule == "lobatto")
            if isinstance(r, CohesiveRun):
                out[f"run{i}.block.d_old"] = np.array(r.block.d_old, copy=True)
                out[f"run{i}.block.dv_old"] = np.array(r.block.dv_old, copy=True)
                out[f"run{i}.block.lam_old"] = np.array(r.block.lam_old, float)
                out[f"run{i}.viscosity"] = np.array(r.law.viscosity, float)
        out["energy"] = np.array(self.energy, copy=True)
        if self.stabilized is not None:
            out["stabilized"] = np.array([self.stabilized["load_factor"], self.stabilized["viscosity"]])
        if self.u_last is not None:
            out["energy.u"], out["energy.f"] = self.u_last.copy(), self.f_last.copy()
        return out

    def restore(self, problem, state: dict[str, np.ndarray]) -> None:
        """Inverse of :meth:`state` on a freshly built problem of the same model: sets the bond
        flags (and rebuilds the constraint operator), the histories and the friction state.
        Raises ValueError naming the entry when ``state`` does not fit this model."""
        def take(key: str, like: np.ndarray | None) -> np.ndarray:
            if key not in state:
                raise ValueError(f"the saved interface state has no '{key}'")
            value = np.asarray(state[key])
            if like is not None and (value.shape != np.shape(like) or value.dtype.kind != np.asarray(like).dtype.kind):
                raise ValueError(f"the saved interface state '{key}' has shape {value.shape} ({value.dtype}), "
                                 f"this model needs {np.shape(like)} ({np.asarray(like).dtype})")
            return value.copy()

        saved_bonds = sorted(k for k in state if k.startswith("bonded."))
        if saved_bonds != sorted(f"bonded.{k}" for k in problem.bonded):
            raise ValueError(f"the saved bond flags are for the interfaces {saved_bonds}, this model has "
                             f"{sorted(f'bonded.{k}' for k in problem.bonded)}")
        runs = {k.split(".")[0] for k in state if k.startswith("run")}
        if len(runs) != len(self.runs):
            raise ValueError(f"the saved state has {len(runs)} interface(s) with a law, this model {len(self.runs)}")
        for k in problem.bonded:
            problem.bonded[k] = take(f"bonded.{k}", problem.bonded[k])
        self.lam = float(take("lam", None))
        moved = False
        for i, r in enumerate(self.runs):
            key = f"run{i}.nodal_contact"
            if isinstance(r, InterfaceRun) and key in state:  # (absent in checkpoints before contact_to_nodes)
                rule = "lobatto" if bool(state[key]) else "gauss"
                if rule != r.law.rule:
                    self._set_rule(problem, r, rule)
                    moved = True
        if moved:
            problem.assembler.add_blocks(problem.extra_blocks)
        for i, r in enumerate(self.runs):
            for name in self._run_arrays(r):
                setattr(r, name, take(f"run{i}.{name}", getattr(r, name)))
            ff = float(take(f"run{i}.first_failure", None))
            r.first_failure = None if np.isnan(ff) else ff
            for name in self.BLOCK_ARRAYS:
                if getattr(_kin(r.block), name) is not None:
                    setattr(_kin(r.block), name, take(f"run{i}.block.{name}", getattr(_kin(r.block), name)))
            if isinstance(r, CohesiveRun):
                r.block.d_old = take(f"run{i}.block.d_old", r.block.d_old)
                r.block.dv_old = take(f"run{i}.block.dv_old", r.block.dv_old)
                r.block.lam_old = float(take(f"run{i}.block.lam_old", None))
                r.set_stick_penalty()
                if f"run{i}.viscosity" in state:  # automatic stabilisation (stabilize) switched it on or off
                    r.law = replace(r.law, viscosity=float(state[f"run{i}.viscosity"]))
                    r.block.law = r.law
            _kin(r.block).active = None
        self.stabilized = ({"load_factor": float(state["stabilized"][0]), "viscosity": float(state["stabilized"][1])}
                           if "stabilized" in state else None)
        if "energy" in state:
            self.energy = np.array(state["energy"], float)
            self.u_last = np.array(state["energy.u"]) if "energy.u" in state else None
            self.f_last = np.array(state["energy.f"]) if "energy.f" in state else None
        self.resolves = 0
        problem.rebuild_constraints()
        self.sync(problem)

    # ------------------------------------------------------------------ stabilisation
    def stabilize(self, eta: float, lam: float) -> bool:
        """Switch on the viscous regularisation (Gao & Bower 2004, :class:`CohesiveBlock`) with
        the time ``eta`` (load-factor units) on every cohesive interface that has none, from the
        converged state at ``lam`` on; ``load_steps`` does this when a step fails through all its
        bisections (``NewtonSettings.stabilize``). The acting damage starts equal to the
        rate-independent one, so the converged state is unchanged; the viscous share of the
        dissipation is booked in the energy ledger. False: nothing to switch on."""
        if not eta > 0 or not self._viscous_on(eta):
            return False
        self.stabilized = {"load_factor": float(lam), "viscosity": float(eta)}
        return True

    def _viscous_on(self, eta: float) -> list:
        """Switch the viscous law with the time ``eta`` on at every cohesive interface that has
        none, the acting damage starting at the rate-independent one; returns those runs."""
        coh = [r for r in self.runs if isinstance(r, CohesiveRun) and r.law.viscosity == 0]
        for r in coh:
            r.law = replace(r.law, viscosity=float(eta))
            r.block.law = r.law
            r.block.dv_old = np.array(r.block.dv_old if r.block.dv_old is not None else r.block.d_old, copy=True)
            r.block.relax_time = 0.0
        return coh

    def relax_begin(self) -> bool:
        """Switch on the viscous law (Gao & Bower 2004) with the unit time η = 1 on every cohesive
        interface that has none, for a relaxation at a fixed load (:func:`~layershell.solver.
        newton.relax`): the pseudo-time of its increments is ``CohesiveBlock.relax_time``. The
        acting damage starts equal to the rate-independent one. False: nothing to switch on."""
        self.relaxing = self._viscous_on(1.0)
        return bool(self.relaxing)

    def relax_time(self, dt: float) -> None:
        """The pseudo-time of the next relaxation increment (in units of η = 1)."""
        for r in self.relaxing:
            r.block.relax_time = float(dt)

    def viscous_lag(self) -> float:
        """max |d - d_v| of the relaxing interfaces at their last commit: how far the acting
        damage still lags behind the rate-independent one (0: relaxed)."""
        return max((float(np.abs(r.block.d_old - r.block.dv_old).max()) if r.block.d_old.size else 0.0
                    for r in self.relaxing), default=0.0)

    def damage_change(self, u: np.ndarray) -> float:
        """max |d(u) - d_old| over the cohesive interfaces: how much the rate-independent damage
        at ``u`` differs from the last commit's."""
        out = 0.0
        for r in self.runs:
            if isinstance(r, CohesiveRun) and r.block.d_old.size:
                r.block.point_state(u)
                out = max(out, float(np.abs(r.block.last_inviscid - r.block.d_old).max()))
        return out

    def relax_end(self) -> None:
        """Back to the rate-independent law on the interfaces :meth:`relax_begin` switched."""
        for r in self.relaxing:
            r.law = replace(r.law, viscosity=0.0)
            r.block.law = r.law
            r.block.relax_time = 0.0
        self.relaxing = []

    def cohesive(self) -> bool:
        """Whether any interface has the cohesive law."""
        return any(isinstance(r, CohesiveRun) for r in self.runs)

    def dissipation(self) -> tuple[float, float]:
        """(fracture, viscous): the energy the cohesive interfaces have dissipated so far."""
        coh = [r for r in self.runs if isinstance(r, CohesiveRun)]
        return sum(float(r.energy[0]) for r in coh), sum(float(r.energy[2]) for r in coh)

    def dissipated_total(self) -> float:
        """Fracture + friction + viscous: all the energy the cohesive interfaces' ledger has
        booked as dissipated so far (the arc length's dissipation constraint measures the same
        from the work, :func:`~layershell.solver.arclength.dissipation_increment`)."""
        return sum(float(r.energy[0] + r.energy[1] + r.energy[2]) for r in self.runs if isinstance(r, CohesiveRun))

    # ------------------------------------------------------------------ results
    def first_failure(self) -> float | None:
        vals = [r.first_failure for r in self.runs if r.first_failure is not None]
        return min(vals) if vals else None

    def debonded_extent(self) -> dict[str, dict[str, float]]:
        """Per interface: released area and the bounding box (x, y) of the released interface
        points in the reference configuration, None where none."""
        areas = self.debonded_area()
        out = {}
        for r in self.runs:
            P = _kin(r.block).X0[_released(r)]
            box = {f"{c}_{m}": (float(getattr(P[:, i], m)()) if P.size else None)
                   for i, c in enumerate("xy") for m in ("min", "max")}
            out[_kin(r.block).itf.name] = {"area": areas[_kin(r.block).itf.name], **box}
        return out

    def debonded_fraction(self) -> float:
        """Released share of all interface area (for step cutting)."""
        a = sum(self.debonded_area().values())
        A = sum(float(_kin(r.block).w0.sum()) for r in self.runs)
        return a / A if A > 0 else 0.0

    def debonded_area(self) -> dict[str, float]:
        return {_kin(r.block).itf.name: float((_kin(r.block).w0 * _released(r)).sum()) for r in self.runs}

    # ------------------------------------------------------------------ cohesive results
    def first_damage(self) -> float | None:
        """Load factor of the first damage at a cohesive interface point (None: none yet)."""
        vals = [float(r.first_damage) for r in self.runs if isinstance(r, CohesiveRun) and np.isfinite(r.first_damage)]
        return min(vals) if vals else None

    def _path_energies(self, problem, u: np.ndarray, lam: float) -> None:
        """External work and the layers' strain energy as path integrals (trapezoid over the
        converged states): W = Σ ½(F_k + F_k+1)·(u_k+1 - u_k) with F the total internal force,
        which at equilibrium is the applied load plus the support reactions - so W includes the
        work of prescribed displacements (displacement control; fixed supports and the bond's
        internal constraint forces do none); U = the same with the layers' internal forces (the
        internal force less the interface blocks' forces)."""
        f, _ = problem.assembler.evaluate(u, tangent=False)
        F = f.copy()
        for b in problem.assembler.extra:
            fe, _ = b.response(u, tangent=False)
            f = f - np.bincount(b.dofs.ravel(), weights=fe.ravel(), minlength=f.size)
        if self.u_last is None:
            self.u_last, self.f_last = np.zeros_like(u), np.zeros((2, u.size))
        du = u - self.u_last
        self.energy = self.energy + 0.5 * np.array([(self.f_last[0] + F) @ du, (self.f_last[1] + f) @ du])
        self.u_last, self.f_last = u.copy(), np.stack([F, f])

    def energies(self, problem, u: np.ndarray) -> dict[str, float] | None:
        """Energy ledger of a model with cohesive interfaces (None without): external work,
        strain energy of the layers, elastic energy of the interfaces, dissipation by fracture,
        friction and viscosity, and the balance error (external - stored - dissipated) relative
        to the external work."""
        coh = [r for r in self.runs if isinstance(r, CohesiveRun)]
        if not coh:
            return None
        W, U = (float(v) for v in self.energy)
        E_itf = sum(r.block.elastic_energy(u) for r in coh)
        frac = sum(float(r.energy[0]) for r in coh)
        fric = sum(float(r.energy[1]) for r in coh)
        visc = sum(float(r.energy[2]) for r in coh)
        err = W - U - E_itf - frac - fric - visc
        return {"external_work": W, "strain_energy": U, "interface_elastic_energy": E_itf,
                "dissipated_fracture": frac, "dissipated_friction": fric, "dissipated_viscous": visc,
                "balance_error": err / max(abs(W), U + E_itf + frac + fric + visc, 1e-300)}


def contact_move_message(move: dict) -> str:
    """The warning for one move of :meth:`InterfaceController.contact_to_nodes`."""
    return (f"at load factor {move['load_factor']:.6g} the contact between debonded layers at the face Gauss points "
            f"(the thesis's points; below {', '.join(repr(m) for m in move['interfaces'])}) found no equilibrium"
            + (f" ({move['reason']})" if move.get("reason") else "")
            + "; from there on it acts at the nodes, as with [[interfaces]] rule = \"lobatto\" (the stress criterion "
            "stays at the Gauss points; summary.json 'contact_moved_to_nodes'). Set rule = \"gauss\" to keep the "
            "Gauss points (the run then stops there) or rule = \"lobatto\" to use the nodes from the start")


def _kin(block):
    """The contact kinematics of a block (a cohesive block holds one)."""
    return getattr(block, "contact", block)


def _released(r) -> np.ndarray:
    """Points that are released (thesis law) or fully damaged (cohesive law)."""
    return r.block.d_old >= FULL_DAMAGE if isinstance(r, CohesiveRun) else r.block.released


def default_cohesive_stiffness(model, itf: Interface, law: CohesiveLaw) -> float:
    """K0 = α E3 / H (Turon, Dávila, Camanho & Costa 2007) with the larger E3/H of the two
    adjacent layers (the thinner, stiffer one), α = ``law.alpha`` (50)."""
    lo, up = model.layers[itf.lower], model.layers[itf.upper]
    return law.alpha * max(lo.material.E3 / lo.thickness.min(), up.material.E3 / up.thickness.min())


def cohesive_softening_estimate(model, itf: Interface, K: float) -> float:
    """The compliance 1/K of the interface relative to the through-thickness compliance of the
    two layers, Σ H/E3 (normal) - an upper estimate of how much the penalty softens the bonded
    stack (the shear ratio, with G < E, is smaller)."""
    lo, up = model.layers[itf.lower], model.layers[itf.upper]
    return (1.0 / K) / (lo.thickness.min() / lo.material.E3 + up.thickness.min() / up.material.E3)


def _cohesive_run(problem, itf: Interface, law: CohesiveLaw, initial_nodes) -> CohesiveRun:
    """A cohesive interface: no bond constraint (both layers keep their DOFs everywhere), the
    cohesive block on the chosen face rule; initially debonded zones start fully damaged."""
    model, dm = problem.model, problem.dm
    K = law.K0 if law.K0 is not None else default_cohesive_stiffness(model, itf, law)
    cb = ContactBlock.build(model, dm, itf, K, rule=law.rule)
    ne, nq = cb.w.shape
    cb.released = np.ones((ne, nq), bool)
    cb.cap, cb.t_n, cb.g_p = np.zeros((ne, nq)), np.zeros((ne, nq, 3)), np.zeros((ne, nq, 3))
    problem.bonded[itf.upper] = np.zeros_like(problem.bonded[itf.upper])
    d0 = np.zeros((ne, nq))
    if initial_nodes is not None:
        init = np.zeros(model.mesh.n_nodes, bool)
        init[initial_nodes] = True
        d0 = np.where(init[cb.conn[:, cb.region]], 1.0, 0.0)
    blk = CohesiveBlock(cb, law, K, d0, dv_old=d0.copy())
    run = CohesiveRun(blk, law, np.zeros((ne, nq)), np.zeros((ne, nq, 3)), np.zeros((ne, nq, 3)), np.zeros(3),
                      np.array(np.nan), d0 > 0, np.zeros((ne, nq)))
    run.set_stick_penalty()
    return run


def _arm(model, k: int, direction: np.ndarray, normal: np.ndarray) -> Arm:
    """Layer ``k`` as an arm of the process-zone estimate along the unit ``direction`` (in the
    plane with unit ``normal``): its smallest thickness, in-plane modulus and transverse shear
    modulus along that direction, E3. A layer held by supports at every node (all directors and
    components, e.g. a rigid substrate) is rigid."""
    ly = model.layers[k]
    mat = ly.material
    if _held(model, k):
        return Arm(float(ly.thickness.min()), np.inf, np.inf, np.inf)
    a1 = np.asarray(ly.direction, float) if ly.direction is not None else np.array([1.0, 0.0, 0.0])
    a1 = a1 - (a1 @ normal) * normal  # its tangent-plane projection; the material axis 1 is at ω from it
    theta = float(np.arctan2(np.cross(a1, direction) @ normal, a1 @ direction))
    E, G, nu = in_plane_modulus(mat, theta - ly.angle)
    return Arm(float(ly.thickness.min()), E, mat.E3, G, nu)


def _held(model, k: int) -> bool:
    """True where supports fix every director and component of layer ``k`` at all its nodes."""
    held = np.zeros((model.mesh.n_nodes, model.layers[k].directors + 1, 3), bool)
    for f in model.fixes:
        if f.layer == k:
            dirs = [d for d in f.directors if d <= model.layers[k].directors]
            held[np.ix_(np.asarray(f.nodes), dirs, list(f.components))] = True
    stacks = [i for i, st in enumerate(model.stacks) if k in st]
    nodes = np.unique(model.mesh.elements[np.isin(model.element_stack, stacks)])
    return bool(nodes.size) and bool(held[nodes].all())


def process_zone_estimate(model, r: CohesiveRun) -> tuple[dict, float, np.ndarray]:
    """The process-zone lengths of a cohesive interface per mode (:mod:`layershell.process_zone`,
    with its penalty K and the two adjacent layers as arms along the finer mesh direction), the
    node spacing h along that direction and that direction (:func:`interface_zone_estimate`)."""
    return interface_zone_estimate(model, r.block.contact.itf, r.law, r.block.K)


def interface_zone_estimate(model, itf: Interface, law: CohesiveLaw, K: float) -> tuple[dict, float, np.ndarray]:
    """:func:`process_zone_estimate` from the model alone (before a run): the interface ``itf``
    with its cohesive ``law`` and penalty ``K``. The node spacing h is half the shorter side of
    the largest elements (the front runs along one side)."""
    X = model.mesh.nodes[model.mesh.elements[itf.elements]]  # (e, 9, 3)
    s1, s3 = X[:, 1] - X[:, 0], X[:, 3] - X[:, 0]
    n1, n3 = np.linalg.norm(s1, axis=-1), np.linalg.norm(s3, axis=-1)
    i1, i3 = int(np.argmax(n1)), int(np.argmax(n3))
    if n1[i1] <= n3[i3]:
        h, e, i = 0.5 * n1[i1], s1[i1] / n1[i1], i1
    else:
        h, e, i = 0.5 * n3[i3], s3[i3] / n3[i3], i3
    nrm = np.cross(s1[i], s3[i])
    nrm = nrm / np.linalg.norm(nrm)
    arms = (_arm(model, itf.lower, e, nrm), _arm(model, itf.upper, e, nrm))
    return zone_lengths(law.G_Ic, law.G_IIc, law.sigma_max, law.tau_max, K, arms), float(h), e


def zone_description(est: dict) -> str:
    """'mode I 0.35 (thick-body estimate), mode II 8.5 (slender-layer estimate)'."""
    kind = {"thick": "thick-body estimate M E' G_c/σ²", "slender": "slender-layer (beam) estimate"}
    return ", ".join(f"mode {m} {est[m]['length']:.4g} ({kind[est[m]['used']]})" for m in ("I", "II"))


def _process_zone_warning(model, r: CohesiveRun, B: float) -> list[str]:
    """Turon et al. (2007): the cohesive process zone should span at least 3 node spacings
    (about 3 elements are usually recommended; here the node spacing of the 9-node elements,
    half an element). Checked when damage starts, with the mode ratio ``B`` = G_II/G_T of the
    points that damaged first: the length l = (1 − B) l_I + B l_II of the mode estimates
    (:func:`process_zone_estimate`)."""
    est, h, _ = process_zone_estimate(model, r)
    lI, lII = est["I"]["length"], est["II"]["length"]
    lcz = (1.0 - B) * lI + B * lII
    if lcz >= 3.0 * h:
        return []
    name = r.block.contact.itf.name
    return [f"interface '{name}': damage started (mode ratio G_II/G = {B:.2f}); its process zone, from the "
            f"onset of damage to complete separation, is estimated at {lcz:.4g} ({zone_description(est)}; "
            f"layershell.process_zone) and spans {lcz / h:.2f} node spacings (h = {h:.4g}), fewer "
            "than 3: the peak load and the debonding load are then mesh dependent (Turon et al. 2007). Refine "
            f"the mesh along the debonding front to a node spacing of at most {lcz / 3:.3g} (elements of "
            f"{2 * lcz / 3:.3g}), or check that G_Ic, G_IIc and the strengths are consistent"]


def _default_stick(model, itf: Interface) -> float:
    """α_T = G_13 / H of the thinner layer: the shear stiffness of that layer per area. Stiffer
    stick penalties make the regularised friction effectively rigid-plastic, and Newton then
    struggles at stick/slip transitions (V5 results are unchanged between 1e8 and 1e9)."""
    lo, up = model.layers[itf.lower], model.layers[itf.upper]
    thin = lo if lo.thickness.min() < up.thickness.min() else up
    return min(thin.material.G31, thin.material.G23) / thin.thickness.min()


def _default_penalty(model, itf: Interface) -> float:
    """α_N = 100 E3,max / H_min of the two layers (MODEL.md §10: try 10²-10³ E/H_min)."""
    lo, up = model.layers[itf.lower], model.layers[itf.upper]
    E = max(lo.material.E3, up.material.E3)
    H = min(lo.thickness.min(), up.thickness.min())
    return 100.0 * E / H
