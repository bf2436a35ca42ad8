"""Report writers: one module per verb, named as the verb and its analysis (``sweep``,
``states``, ``continuation``, ...), each with the ``write`` function the verb registry names;
they write the verb's files (tables, arrays, the figures of :mod:`vibrogear.report.plots`),
atomically.  ``sweep_files`` and ``branch_files`` are the sweep's and the branches' file
formats, read back by the verbs that reuse them."""
