"""Every figure: the shared style, the paper's figures, predictions, the sweep, the compensation drift, the cross-dataset figure, and their captions."""
