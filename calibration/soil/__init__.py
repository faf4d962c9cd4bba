"""The optimizer competition on the soil block (the study's Table 4-3): the block model, its mesh, the
methods (ARSM and the GA / Monte Carlo baselines) and the report."""
