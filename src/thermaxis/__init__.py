"""thermaxis: thermal positioning error of machine-tool linear axes.

Reproduces Xu et al., "Research on decoupling and step-by-step modelling of thermal
positioning error of the linear axis" (Chinese Journal of Scientific Instrument,
DOI 10.19650/j.cnki.cjsi.J2209628), and goes beyond it.
"""

__version__ = "0.1.0"
