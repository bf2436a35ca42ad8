"""The option sections of a scene: one module per verb with options, named as the verb
(``map``, ``nvh``, ``runup``, ``states``, ``nnm``, ``optimize``, ``findings``, ``housing`` for
the housing studies) and the sections every scene may have (``common``), each validated once,
at load time; they build the solvers' own option objects (:mod:`vibrogear.config.options`)."""
