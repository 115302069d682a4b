"""One module per problem kind, each defining one :class:`~gtmodel.problems.base.ProblemKind`.

A kind is thin: its file schema (defined in a light module of
:mod:`gtmodel.problems.kinds.schemas`, so that a file is validated before the kind's
solvers are imported), ``load`` (the validated file -> the domain's
declaration, naming TOML fields in errors), ``write`` (files and summary fields) and its
study columns. What is solved, and how, lives in the domain packages (rockit's split
between declaring a problem, choosing a method and choosing a solver):

==================================  ====================================================
kind                                declaration (with its ``solve``)
==================================  ====================================================
``point_to_point``                  :class:`gtmodel.trajectory.PointToPoint`
``path_constrained``                :mod:`gtmodel.trajectory.path_constrained.declared`
``optimal_control``                 :mod:`gtmodel.trajectory.model_ocp`
``calibration``                     :mod:`gtmodel.calibration.comparison`
``elasto_geometric_calibration``    :mod:`gtmodel.calibration.elasto_geometric_declared`
``joint_stiffness_calibration``     :mod:`gtmodel.calibration.joint_stiffness_declared`
``dynamic_identification``          :mod:`gtmodel.calibration.identification.declared`
``ilc``                             :mod:`gtmodel.estimation.ilc.cases`
``state_estimation``                :mod:`gtmodel.estimation.fusion.declared`
``correction_stability``            :mod:`gtmodel.estimation.closed_loop.declared`
``replay`` (formerly ``tracking``)  here (it solves another problem file first), replayed
                                    by :mod:`gtmodel.estimation.closed_loop.replay`
==================================  ====================================================

The loop-controller files (``mpc``, ``tracking_controller``, ``estimator_ilc``) are declared
kinds too, with light schemas here (:mod:`gtmodel.problems.kinds.schemas.loop`, ``mpc``,
``tracking_controller``, ``estimator_ilc``), listed in
:data:`gtmodel.problems.registry.LOOP_KINDS` and built by code generation, not solved.

The method and solver settings of the optimisation kinds are
:class:`gtmodel.modeling.ocp.methods.Collocation` and
:class:`gtmodel.modeling.ocp.methods.SolverSettings`.
"""
