"""The schemas of the problem kinds, light: one module per kind, validated before the kind is imported.

Each module defines a kind's :class:`~gtmodel.problems.schema.ProblemSchema` subclass and
its section models, importing only the standard library, pydantic and the light modules
of gtmodel (:mod:`gtmodel.problems.schema`, :mod:`gtmodel.errors`, :mod:`gtmodel.defaults`),
never a solver. The registry (:mod:`gtmodel.problems.registry`) names each schema by its
dotted path, so that :func:`gtmodel.problems.run.load_problem` reports a bad field in a
fraction of a second and imports the kind (its solvers) only for a valid file. The kind's
``schema`` attribute is the same class.
"""
