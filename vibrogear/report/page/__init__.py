"""``report.html``: the page (``html_report``), its pieces (``html_parts``, ``load_path``), the
words it uses (``glossary``) and the captions of its figures (``captions``)."""
