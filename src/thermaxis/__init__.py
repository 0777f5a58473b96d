"""thermaxis: thermal positioning error of machine-tool linear axes.

Reproduces Xu et al., "Research on decoupling and step-by-step modelling of thermal
positioning error of the linear axis" (Chinese Journal of Scientific Instrument,
DOI 10.19650/j.cnki.cjsi.J2209628), and goes beyond it.
"""

import sys

# jsonschema imports the optional IRI-syntax checker rfc3987_syntax when present
# (pulled in by jupyter), which builds a parser grammar on import and costs ~2.5 s in
# every workflow job. No schema of ours uses the "iri" formats, so the checker is
# hidden; jsonschema treats it as not installed.
if "rfc3987_syntax" not in sys.modules:
    sys.modules["rfc3987_syntax"] = None

__version__ = "0.1.0"
