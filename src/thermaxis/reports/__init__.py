"""Reports: HTML pieces, data summaries, notebook execution, the index page, provenance and the cross-dataset summary."""
