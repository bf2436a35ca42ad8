"""Report writers: one module per verb, named as the verb and its analysis (``sweep``,
``states``, ``continuation``, ...), each with the ``write`` function the verb registry names;
they write the verb's files (tables, arrays, the figures of :mod:`vibrogear.report.plots`),
atomically, the sweep's and the branches' in the formats of :mod:`vibrogear.report.sweep_files`
and :mod:`vibrogear.report.branch_files`."""
