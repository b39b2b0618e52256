"""Every result of the paper regenerated: the figure runs and their ensembles, the figures, the claims
report and the MuJoCo comparison (``cobra-ref figures``), with the analysis they share."""
