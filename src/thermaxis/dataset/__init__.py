"""Reading a dataset: the validating reader of the raw layout, path and file safety, plausibility checks, the importer of wide logger tables and the dataset summary."""
