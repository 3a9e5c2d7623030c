"""The built-in accuracy measures, one module each: ``worst_case``, ``rss``, ``mc_quantile``, ``yield``
(:mod:`.statistical_yield`). They are found through :mod:`evotol.measures.linear.registry`."""
