"""gtmodel.trajectory (see DESIGN.md)."""
