"""The sweep over selection settings, cluster counts, algorithms and decoupling degree: its plan and its evaluation."""
