"""The option sections of a scene: one module per verb with options, named as the verb
(``map``, ``nvh``, ``runup``, ``states``, ``nnm``, ``optimize``, ``findings``, ``housing`` for
the housing studies), the sections every scene may have (``common``) and the solvers' own option
objects (``options``), each validated once, at load time."""
