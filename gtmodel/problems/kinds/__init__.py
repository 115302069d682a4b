"""One module per problem kind, each defining one :class:`~gtmodel.problems.base.ProblemKind`."""
