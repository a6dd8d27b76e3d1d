"""report/: plots, tables and the HTML report."""
