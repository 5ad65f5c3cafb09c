"""The design solver: bounded, constrained, exact, with implicit derivatives.

The search works on variables scaled to their bound width, y = (x - lower) / scale in
[0, y_max], the objective scaled to a unit gradient at the start (or, next to a
stationary point, to a gradient of ``SQP.gradient_floor`` times its Hessian) and each constraint row
to its target or limit. It has two stages:

1. sequential quadratic programming (ours): at each accepted point the quadratic model
   (the Hessian of the Lagrangian at the least-norm multipliers of the last step's active
   rows, made definite by taking its eigenvalues' moduli, the smallest raised to a floor
   except along the rows that fix the step: the targets, and the limits that a first
   solve holds, in a second solve, :func:`_settled_step`; where the last step's active
   rows are dependent at a point that nearly meets them, made definite on their null
   space apart from the rest) is
   minimised subject to the linearised targets and limits, the box and a radius (an
   inf-norm trust region: none until the line search first shortens a step, then the
   length it shortened the last one to, doubled after each whole step that reaches
   it), with elastic slacks so that the subproblem is always feasible
   (:mod:`magdesign.design._qp`); a backtracking line search on the exact l1 merit
   function f + nu |violation|_1 (nu at least twice the multipliers and 1, falling halfway
   towards that at each point: Powell's update) accepts the step, along a descent direction
   against the largest merit of the last few points (nonmonotone, so that a curved constraint's
   higher-order violation does not stop the steps where the objective is flat). A whole
   step that the merit rejects is tried once more along an arc bent by its second-order
   correction, which keeps the active constraints met to second order (from the
   Hessians the search has already; it overcomes the Maratos effect on curved
   constraints), and after a step that needed it the next is bent from its first try.
   Where the step vanishes (the subproblem solved once more with the Hessian at its own
   multipliers: the last point's, after an infeasible subproblem priced at the elastic
   cost, make steps vanish where the point is not stationary) the point is stationary;
   "successful" then also needs the reduced Hessian of the Lagrangian on the null space
   of the active constraints to be positive semi-definite, and a point that fails it is
   left along its direction of negative curvature, bent along the active constraints (at
   most ``SQP.escapes`` times, then "not_a_minimum"). A stationary point whose least
   curvature is too small to tell (x^3 at 0), or which the steps reached only linearly
   (a stationary start too, which no steps reached), is probed on both sides of a
   direction that combines all its flat ones, then of the steps' approach
   (:func:`_least_curvature`), at a few lengths before it is accepted; a problem without
   objective has no minimum to confirm and is not probed.
   This stage is ours because it chooses the active set, which no JAX library does:
   optimistix's solvers take no constraints or bounds, and jaxopt's bounded QP (BoxOSQP)
   is too inexact for it (measured in benchmarks/design.py).
2. polish (optimistix, to a tenth of the tolerance): with the active set of the last subproblem, the KKT system
   (stationarity on the free variables, targets and active limits as equations, active
   bounds as fixed variables) is solved by optimistix's Newton (``optimistix.Newton``),
   stepped in the search's own loop once the search ends: optimistix's interactive use
   of a solver (its ``init``, ``step`` and ``terminate``; the steps and stopping rule of
   ``optimistix.root_find``), so that one place of the program evaluates the model and
   XLA compiles it once, where a separate root find would compile it again. Newton's first step
   is taken from the search's last jet, so the model is not evaluated again where the
   search has just evaluated it. A problem without objective is a feasibility problem,
   whose equations (targets, active limits, fixed variables; in general fewer than the
   unknowns) Newton through an SVD solves as Gauss-Newton with minimum-norm steps (see
   :func:`_newton`; ``optimistix.least_squares`` would differentiate grad |r|^2 / 2,
   which traces second derivatives: on the spin-valve example that would take the compile of a
   batched solve from under 1 GB to over 11 GB). The linear systems go
   to :mod:`magdesign.design._linear`: LU where the Jacobian is square and well
   conditioned, else an SVD, whose minimum-norm step handles rank-deficient Jacobians
   (degenerate active sets, manifolds of solutions). The optimum's implicit derivatives
   (forward mode, with respect to the target values, limit bounds and fixed inputs) are
   those of ``optimistix.ImplicitAdjoint``, asked at the polished root with the model's
   jet from the polish's last evaluation there (:func:`_implicit_derivatives`).

Everything after the Python-level unpacking is one jitted, vmappable function of a fixed
problem structure; the outcome is a :class:`DesignStatus`, never an exception. The search
and the polish are one loop whose body evaluates the model's jet (values, Jacobian,
Hessians) once, at the point the search tries or at Newton's iterate, so XLA compiles one
copy of the model for both.
"""
