"""The MPC's horizon problem by single shooting (``solver = "sqpmethod"``) and the states inside its periods.

The NLP of :mod:`gtmodel.control.mpc` over the blocked inputs and the slacks: the states
eliminated by the prediction ``x_{j+1} = F(x_j, u_j)``, the residuals of the quadratic cost
and their Gauss-Newton Hessian, and the constraint rows of
:class:`~gtmodel.control.mpc_constraints.MPCConstraints` at the constrained predicted states
and, with ``between``, at the states after each substep of the prediction within the periods
ending there (:func:`period_states`, shared with the multiple shooting of
:mod:`gtmodel.control.mpc_fatrop`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

__all__ = ["UNROLLED_HESSIAN_MAX", "between_rows", "period_states", "single_shooting_nlp", "single_shooting_rti"]


def between_rows(c: Any) -> int:
    """States constrained inside each constrained period besides its end (0: the rows act at the samples only).

    Parameters
    ----------
    c : MPCController
        The MPC.

    Returns
    -------
    int
        ``substeps - 1`` of the prediction when the constraints have ``between`` and the
        controller its :attr:`~gtmodel.control.mpc.MPCController.substep_states`, else 0.
    """
    cons = c.constraints
    if cons is None or not cons.between or c.substep_states is None:
        return 0
    return int(c.substep_states.size2_out(0)) - 1


def period_states(c: Any, x: Any, u: Any) -> tuple[Any, list[Any]]:
    """The prediction over one period and the states between its samples that carry constraint rows.

    Parameters
    ----------
    c : MPCController
        The MPC.
    x, u : casadi.MX
        ``(nx,1)`` state at the period's start and ``(nu,1)`` its held input.

    Returns
    -------
    x_next : casadi.MX
        ``(nx,1)`` the predicted state at the period's end (:attr:`~gtmodel.control.mpc.MPCController.step`).
    inside : list of casadi.MX
        ``(nx,1)`` the states after each substep but the last (:func:`between_rows` of them;
        the same operations as the step's, whose last column is ``x_next``).
    """
    m = between_rows(c)
    if not m:
        return c.step(x, u), []
    s = c.substep_states(x, u)
    return s[:, m], [s[:, i] for i in range(m)]


def _with_jacobian(fun: ca.Function, nx: int, nu: int, name: str) -> ca.Function:
    """``name(x, u) -> (y, dy/dx, dy/du)`` of a stage Function ``fun(x, u)`` (its output as a column ``y``), in SX."""
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
    y = ca.vec(fun(x, u))
    return ca.Function(name, [x, u], [y, ca.jacobian(y, x), ca.jacobian(y, u)], ["x", "u"], ["y", "y_x", "y_u"])


def _selection(n: int, nz: int, start: int) -> ca.DM:
    """``(n, nz)`` the structurally sparse selection of entries ``start .. start + n - 1`` of ``nz``."""
    return ca.DM.triplet(list(range(n)), list(range(start, start + n)), ca.DM.ones(n), n, nz)


#: The Gauss-Newton Hessian's state share ``S' Q S`` of a stage is written out in the stage's SX Function while
#: ``nx nz^2`` (``nz`` the NLP's variables) is at most this, else one dense product of the state residuals' Jacobian
#: in MX with the Jacobian's structural zeros (the inputs of later blocks): unrolled, the belt drive's step
#: (``nx nz^2`` = 2,420) is 14 % faster in median; beyond, the unrolled products fill the generated C (the composed
#: motor unblocked at horizon 200: 6 of its 8.8 MB; 4.1 MB with the product), and a dense product does three times the
#: work (that motor at horizon 100: 1.55x the step time of CasADi's ``jacobian()``; 1.0x with the zeros).
UNROLLED_HESSIAN_MAX = 10_000


def _stage_sensitivities(c: Any, fun: ca.Function, nz: int, rows: bool, hessian: bool = True) -> ca.Function:
    """One stage of the prediction with its sensitivities, dense in SX (see :func:`_single_shooting`).

    ``stage(x, u, u_row, S, E, E_row, Q, x_ref) -> (x_next, S_next, g, G, H, q)``: ``fun``'s states ``y`` (``(nx, m + 1)``,
    the last ``x_next``), ``S_next = dy/dx S + dy/du E`` of the last; with ``rows`` the stage's constraint rows ``g`` (at
    the states inside with ``u``, at ``x_next`` with ``u_row``; without the slacks) and their Jacobian ``G`` in ``w``
    (the slacks' columns included), else empty; the state residual's share of the Gauss-Newton Hessian and gradient,
    ``H = S_next' Q S_next`` (without ``hessian``: ``(1, 1)`` zero) and ``q = S_next' Q (x_next - x_ref)``.
    """
    nx, nu, cons = c.nx, c.nu, c.constraints
    x, u, u_row = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("u_row", nu)
    S, E, E_row = ca.SX.sym("S", nx, nz), ca.SX.sym("E", nu, nz), ca.SX.sym("E_row", nu, nz)
    Q, x_ref = ca.SX.sym("Q", nx, nx), ca.SX.sym("x_ref", nx)
    y = ca.vec(fun(x, u))
    sy = ca.mtimes(ca.jacobian(y, x), S) + ca.mtimes(ca.jacobian(y, u), E)
    m = y.numel() // nx - 1
    g, G = [], []
    if rows:
        xv, uv = ca.SX.sym("xv", nx), ca.SX.sym("uv", nu)
        rv = cons.rows(xv, uv)
        row_fun = ca.Function("rows", [xv, uv], [rv, ca.jacobian(rv, xv), ca.jacobian(rv, uv)])
        n_slack = c.n_slack
        slack = ca.SX(_selection(n_slack, nz, nz - n_slack)) if n_slack else ca.SX(rv.numel(), nz)
        for i in range(m + 1):
            ui, ei = (u, E) if i < m else (u_row, E_row)
            v, vx, vu = row_fun(y[i * nx:(i + 1) * nx], ui)
            g.append(v)
            G.append(ca.mtimes(vx, sy[i * nx:(i + 1) * nx, :]) + ca.mtimes(vu, ei) + slack)
    x_next, s_next = y[m * nx:], sy[m * nx:, :]
    qs = ca.mtimes(Q, s_next)
    return ca.Function("stage_rows" if rows else "stage", [x, u, u_row, S, E, E_row, Q, x_ref],
                       [x_next, s_next, ca.vertcat(*g), ca.vertcat(*G), ca.mtimes(s_next.T, qs) if hessian else ca.SX(1, 1),
                        ca.mtimes(qs.T, x_next - x_ref)],
                       ["x", "u", "u_row", "S", "E", "E_row", "Q", "x_ref"], ["x_next", "S_next", "g", "G", "H", "q"])


class _Chain:
    """The stage functions of the prediction with their sensitivities, for :func:`_single_shooting`'s chain rule."""

    def __init__(self, c: Any, nz: int):
        self.hessian = c.nx * nz * nz <= UNROLLED_HESSIAN_MAX  # the stages' Hessian shares unrolled (else one product)
        self.step = _stage_sensitivities(c, c.step, nz, False, self.hessian)
        self.rows = None
        if c.constraints is not None:
            self.rows = _stage_sensitivities(c, c.substep_states if between_rows(c) else c.step, nz, True, self.hessian)


def _single_shooting(c: Any, sqrt_psd: Any, sensitivities: bool = False) -> tuple:
    """``(w, p, r, g, f, rho, J_r, J_g)`` of :func:`single_shooting_nlp`: its variables, parameters, cost residuals,
    rows, cost, penalty and, with ``sensitivities``, the Jacobians of ``r`` and ``g`` in ``w`` (else None).

    The Jacobians by the chain rule along the prediction: each stage's Jacobians ``dF/dx``, ``dF/du`` (one SX Function
    for the steps, one for the states inside the constrained periods, each called once per stage) carry the states'
    sensitivity ``S_{j+1} = F_x S_j + F_u E_j`` (``E_j`` selects period ``j``'s block) — the forward sensitivity
    sweep a ``jacobian`` of the whole prediction would run, in a few small functions rather than one derivative
    function per number of directions (a belt drive's step: 2.6 MB of machine code, most of it read each period).
    """
    H, nx, nu, b = c.horizon, c.nx, c.nu, c.horizon // c.blocks
    W = ca.MX.sym("w", nu, c.blocks)
    s = ca.MX.sym("s", c.n_slack)
    x0 = ca.MX.sym("x0", nx)
    xr = ca.MX.sym("xr", nx, H)
    ur = ca.MX.sym("ur", nu, H)
    Lq, Lf, Lr = (ca.DM(sqrt_psd(m)) for m in (c.Q, c.Qf, c.R))
    up = None if c.R_rate is None else ca.MX.sym("u_prev", nu)  # the input acting before the horizon's first
    Lrate = None if up is None else ca.DM(sqrt_psd(c.R_rate))
    cons = c.constraints
    slack = s if c.n_slack else 0
    nz = nu * c.blocks + c.n_slack
    chain = _Chain(c, nz) if sensitivities else None

    def pick(j: int) -> ca.DM:  # E_j: the inputs of period j's block among w
        return _selection(nu, nz, (j // b) * nu)

    x, sx = x0, ca.MX(nx, nz)
    res, rows, jres, jrows, prev, e_prev = [], [], [], [], up, None
    # J_r' J_r and J_r' r: the states' shares from the stages; the inputs' residuals, linear in w, apart (their Hessian
    # a constant summed here, their gradient one product at the end: a constant added to each stage's share would be
    # written into the C densely, nz^2 numbers per stage)
    gn, jtr, gn_inputs, inputs = [], [], ca.DM(nz, nz), []

    def residual(value: Any, jac: ca.DM) -> None:  # a residual linear in w with a constant Jacobian
        nonlocal gn_inputs
        res.append(value)
        jres.append(jac)
        gn_inputs += ca.mtimes(jac.T, jac)
        inputs.append((value, jac))

    stages = set() if cons is None else set(cons.stages(H))
    for j in range(H):
        u, e = W[:, j // b], pick(j)
        residual(ca.mtimes(Lr, u - ur[:, j]), ca.mtimes(Lr, e))
        if up is not None and j % b == 0:  # the input's change at each block's start (within a block: none)
            residual(ca.mtimes(Lrate, u - prev), ca.mtimes(Lrate, e if e_prev is None else e - e_prev))
            prev, e_prev = u, e
        j_row = min(j + 1, H - 1)  # x_{j+1}'s row with the input of its own period; between the samples the period's own
        L = Lf if j == H - 1 else Lq
        if chain is not None:
            fun = chain.rows if j + 1 in stages else chain.step
            x, sx, v, jv, hj, qj = fun(x, u, W[:, j_row // b], ca.densify(sx), ca.densify(e), ca.densify(pick(j_row)),
                                       ca.densify(ca.mtimes(L.T, L)), xr[:, j])
            if not chain.hessian:  # x_{j+1}'s residual's Jacobian with its structural zeros: the inputs of later blocks, the slacks
                k = (j // b + 1) * nu
                hj = ca.horzcat(ca.mtimes(L, sx[:, :k]), ca.MX(nx, nz - k))
            gn, jtr = gn + [hj], jtr + [qj]
            if j + 1 in stages:
                rows.append(v + ca.repmat(slack, v.numel() // max(c.n_slack, 1), 1) if c.n_slack else v)
                jrows.append(jv)
        elif j + 1 in stages:
            x, inside = period_states(c, x, u)
            rows += [cons.rows(xi, u) + slack for xi in inside]
            rows.append(cons.rows(x, W[:, j_row // b]) + slack)
        else:
            x = c.step(x, u)
        res.append(ca.mtimes(L, x - xr[:, j]))
        jres.append(None if chain is None else ca.mtimes(L, sx))
    r = ca.vertcat(*res)
    w, p = ca.vertcat(ca.vec(W), s), ca.vertcat(x0, ca.vec(xr), ca.vec(ur), *([] if up is None else [up]))
    # g: first one inactive linear row (bounds -inf, inf; see QP_ROW): CasADi 3.8's qrqp reads and
    # writes one entry past its work block on a QP with bounds only (valgrind:
    # casadi_qrqp_dual_blocking); with one constraint row it stays inside. Then the constraint rows >= 0
    g = ca.vertcat(w[0], *rows)
    rho = 0.0 if cons is None else cons.weight
    f = ca.sumsqr(r) + rho * (ca.sum1(s) + ca.sumsqr(s))
    if chain is None:
        return w, p, r, g, f, rho, None
    jtr.append(ca.mtimes(ca.vertcat(*[a for _, a in inputs]).T, ca.vertcat(*[v for v, _ in inputs])))
    if not chain.hessian:  # gn: the state residuals' Jacobians, their share one sparse product (a third of the dense one's work)
        states = ca.vertcat(*gn)
        gn = [ca.mtimes(states.T, states)]
    return w, p, r, g, f, rho, {"J_r": ca.vertcat(*jres), "J_g": ca.vertcat(_selection(1, nz, 0), *jrows), "JtJ": gn_inputs + sum(gn),
                                "Jtr": sum(jtr)}


def single_shooting_nlp(c: Any, sqrt_psd: Any) -> tuple[dict[str, ca.MX], ca.Function]:
    """The single-shooting NLP of an MPC over its blocked inputs (and slacks) and its Gauss-Newton Hessian.

    Parameters
    ----------
    c : MPCController
        The MPC.
    sqrt_psd : callable
        ``L`` with ``L^T L = M`` of a weight matrix.

    Returns
    -------
    nlp : dict
        ``x`` (``nw + n_slack``), ``p`` (:meth:`~gtmodel.control.mpc.MPCController.parameters`),
        ``f``, ``g`` (one inactive row, then the constraint rows ``>= 0``: per constrained
        predicted state ``x_j``, the rows of the states inside period ``j - 1`` then those of
        ``x_j``).
    hess : casadi.Function
        ``nlp_hess_l(x, p, lam_f, lam_g) -> hess_gamma_x_x``: ``2 lam_f (J_r^T J_r + diag(0, rho))``.
    """
    w, p, r, g, f, rho, _ = _single_shooting(c, sqrt_psd)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
    jr = ca.jacobian(r, w)
    gn = ca.mtimes(jr.T, jr) + ca.diag(ca.vertcat(ca.DM.zeros(c.nw), rho * ca.DM.ones(c.n_slack)))
    hess = ca.Function("nlp_hess_l", [w, p, lam_f, lam_g], [2 * lam_f * ca.densify(gn)],
                       ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
    return {"x": w, "p": p, "f": f, "g": g}, hess


#: The line search of CasADi's ``sqpmethod`` (3.8, its defaults) that the step's iteration repeats:
#: at most ``LS_TRIES`` trial steps, each ``LS_BETA`` times the last, the Armijo factor ``LS_C1`` on the
#: L1 merit function, the penalty ``LS_SIGMA_FACTOR`` times the largest QP multiplier.
LS_TRIES, LS_BETA, LS_C1, LS_SIGMA_FACTOR = 3, 0.8, 1e-4, 1.01


def _violation(z: Any, lb: Any, ub: Any) -> Any:
    """``sum(max(0, lb - z) + max(0, z - ub))``: the L1 violation of bounds (infinite bounds count 0)."""
    return ca.sum1(ca.fmax(0, lb - z)) + ca.sum1(ca.fmax(0, z - ub))


def _line_search(fg: ca.Function, nz: int, ng: int, npar: int) -> ca.Function:
    """The step length of ``sqpmethod``'s backtracking line search (:data:`LS_TRIES` trials), each trial's
    prediction evaluated only when the one before was refused (a ``Switch``: the later trials' branch).

    ``ls(z, dz, p, lbx, ubx, lbg, ubg, merit, slope, sigma) -> t``: ``merit`` the L1 merit at ``z``,
    ``slope`` its directional derivative's model ``grad' dz - sigma viol(z)``.
    """
    Z, D, P = ca.MX.sym("z", nz), ca.MX.sym("dz", nz), ca.MX.sym("p", npar)
    LBX, UBX, LBG, UBG = ca.MX.sym("lbx", nz), ca.MX.sym("ubx", nz), ca.MX.sym("lbg", ng), ca.MX.sym("ubg", ng)
    M, S, SIG = ca.MX.sym("merit"), ca.MX.sym("slope"), ca.MX.sym("sigma")
    args = [Z, D, P, LBX, UBX, LBG, UBG, M, S, SIG]

    def accepted(t: float) -> ca.MX:
        f, g = fg(Z + t * D, P)
        return f + SIG * (_violation(Z + t * D, LBX, UBX) + _violation(g, LBG, UBG)) <= M + t * LS_C1 * S

    t_last = LS_BETA ** (LS_TRIES - 1)  # the last trial is taken whatever its merit (sqpmethod: "not successful, but we accept it")
    later = ca.Function("ls_last", args, [ca.DM(t_last)])
    for k in range(LS_TRIES - 2, -1, -1):  # trial k: t = beta^k, accepted, or the trials after it
        t = LS_BETA ** k
        here = ca.Function(f"ls_{k}_taken", args, [ca.DM(t)])
        later = ca.Function(f"ls_{k}", args, [ca.Function.if_else(f"ls_{k}_switch", here, later)(accepted(t), *args)])
    return later


def single_shooting_rti(c: Any, sqrt_psd: Any, qp_options: dict, iterations: int | None = None,
                        tighten: tuple[Any, int] | None = None) -> ca.Function:
    """The MPC's real-time iteration(s) on the single-shooting NLP, each QP by the MPC's ``qpsol``.

    One iteration (Diehl, Bock & Schloeder, SIAM J. Control Optim. 43 (2005)): the cost residuals
    ``r``, the rows ``g`` and their Jacobians at ``w`` in one forward sensitivity sweep of the prediction
    (the chain rule of the stages' Jacobians, :func:`_single_shooting`), the Gauss-Newton QP (Hessian ``2 (J_r^T J_r + diag(0, rho))``, gradient
    ``2 J_r^T r + (0, rho (1 + 2 s))``, the rows linearised, the bounds shifted by ``w``), then
    ``sqpmethod``'s backtracking line search on the L1 merit ``f + sigma viol`` (``sigma`` 1.01 times
    the largest QP multiplier, kept over the iterations; trial steps 1, 0.8, 0.64, the last taken
    whatever its merit; Armijo factor 1e-4; :data:`LS_TRIES`): the first trial's prediction is
    evaluated every period, the second's only when the first is refused. CasADi's ``sqpmethod``
    with one iteration computes the same step but evaluates the rows' Jacobian again at its
    result and the residuals' Jacobian apart for its Hessian (three sensitivity sweeps).

    Parameters
    ----------
    c : MPCController
        The MPC (single shooting: :func:`single_shooting_nlp`).
    sqrt_psd : callable
        ``L`` with ``L^T L = M`` of a weight matrix.
    qp_options : dict
        Options of the QP solver ``c.qpsol``.
    iterations : int, optional
        Iterations (default ``c.sqp_iterations``).
    tighten : tuple of (callable, int), optional
        ``(rows, n_e)``: the constraint rows' lower bounds ``rows(nominal, x0, p, e)`` from the rows at ``x0`` (its
        first linearisation's, less the slacks), ``x0``, ``p`` and ``n_e`` more inputs ``e`` (the step's back-off:
        :func:`~gtmodel.control.mpc_memory.backoff_rows`), for every iteration; ``lbg`` then bounds the first row only.
        Default None: ``lbg`` as given.

    Returns
    -------
    casadi.Function
        ``rti(x0 (nw + n_slack,1), p, lbx, ubx, lbg, ubg[, e]) -> (x (nw + n_slack,1), f (1,1))``: the arguments
        of :meth:`~gtmodel.control.mpc.MPCController.nlp_solver`'s call (and ``e``); ``x`` after the iterations, ``f``
        the last QP's model of the cost at the step taken (NaN where the prediction at the last iterate is).
    """
    w, p, r, g, f, rho, sens = _single_shooting(c, sqrt_psd, sensitivities=True)
    k_it = c.sqp_iterations if iterations is None else int(iterations)
    jg = sens["J_g"]
    s = w[c.nw:]
    hess = 2 * ca.densify(sens["JtJ"] + ca.diag(ca.vertcat(ca.DM.zeros(c.nw), rho * ca.DM.ones(c.n_slack))))
    grad = 2 * sens["Jtr"] + ca.vertcat(ca.DM.zeros(c.nw), rho * (1 + 2 * s))
    lin = ca.Function("lin", [w, p], [f, g, hess, grad, jg], ["w", "p"], ["f", "g", "h", "grad", "jac_g"])
    w1, p1, _, g1, f1, _, _ = _single_shooting(c, sqrt_psd)  # the trial points' prediction, without the sensitivities
    search = _line_search(ca.Function("fg", [w1, p1], [f1, g1]), w.numel(), g.numel(), p.numel())
    qp = ca.conic("mpc_qp", c.qpsol, {"h": hess.sparsity(), "a": jg.sparsity()}, qp_options)
    Z, P = ca.MX.sym("x0", w.numel()), ca.MX.sym("p", p.numel())
    LBX, UBX, LBG, UBG = ca.MX.sym("lbx", w.numel()), ca.MX.sym("ubx", w.numel()), ca.MX.sym("lbg", g.numel()), ca.MX.sym("ubg", g.numel())
    LBG_IN = LBG
    E = [ca.MX.sym("e", tighten[1])] if tighten else []
    z, cost, sigma = Z, None, 0.0
    for it in range(k_it):
        fz, gz, hz, gradz, jz = lin(z, P)
        if tighten and it == 0:  # the rows under the warm start, less its slacks
            nominal = gz[1:] - (ca.repmat(Z[c.nw:], (g.numel() - 1) // c.n_slack, 1) if c.n_slack else 0)
            LBG = ca.vertcat(LBG[0], tighten[0](nominal, Z, P, E[0]))
        sol = qp(h=hz, g=gradz, a=jz, lba=LBG - gz, uba=UBG - gz, lbx=LBX - z, ubx=UBX - z)
        dz = sol["x"]
        sigma = ca.fmax(sigma, LS_SIGMA_FACTOR * ca.fmax(ca.norm_inf(sol["lam_x"]), ca.norm_inf(sol["lam_a"])))
        viol = _violation(z, LBX, UBX) + _violation(gz, LBG, UBG)
        t = search(z, dz, P, LBX, UBX, LBG, UBG, fz + sigma * viol, ca.dot(gradz, dz) - sigma * viol, sigma)
        z, cost = z + t * dz, fz + t * ca.dot(gradz, dz) + 0.5 * t**2 * ca.bilin(hz, dz, dz)
    args = [Z, P, LBX, UBX, LBG_IN, UBG] + E
    return ca.Function("rti", args, [z, cost], ["x0", "p", "lbx", "ubx", "lbg", "ubg"] + ["e"] * len(E), ["x", "f"])
