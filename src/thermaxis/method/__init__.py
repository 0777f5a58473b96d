"""The paper's method: slope/intercept decoupling, sensitive-point selection, the models, the metrics and the leave-one-condition-out folds."""
