"""Analysis plugins: the identification chain of the paper, one module per plugin."""
