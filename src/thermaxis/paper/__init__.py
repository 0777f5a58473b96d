"""The paper's published values (package data), the audit of every published number and Table 5."""
