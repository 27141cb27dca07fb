"""The model: a net's arrays and loads, material laws, time histories, the builders
of nets, derived measures and memory estimates (arrays only: no solver, no files)."""
