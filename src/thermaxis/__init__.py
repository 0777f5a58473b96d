"""thermaxis: thermal positioning error of machine-tool linear axes.

Reproduces Xu et al., "Research on decoupling and step-by-step modelling of thermal
positioning error of the linear axis" (Chinese Journal of Scientific Instrument,
DOI 10.19650/j.cnki.cjsi.J2209628), and goes beyond it.

The library is a subpackage per stage of the workflow: ``dataset``, ``cleaning``,
``method``, ``sweep``, ``compensation``, ``paper``, ``figures``, ``reports``,
``pipeline`` (the Snakemake glue) and ``twin``. The names most users need are
available here, imported on first use so that ``import thermaxis`` stays instant::

    from thermaxis import Settings, load_dataset, DecoupledAxisModel, Compensator
"""

from thermaxis.lazy import lazy_names

__version__ = "0.1.0"

_PUBLIC = {
    "Settings": "thermaxis.config",
    "DataError": "thermaxis.errors",
    "load_dataset": "thermaxis.dataset.reader",
    "DecoupledAxisModel": "thermaxis.method.estimators",
    "PointwiseAxisModel": "thermaxis.method.estimators",
    "Compensator": "thermaxis.compensation.runtime",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
