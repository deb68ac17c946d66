"""Benchmarks behind ``zendock bench``: measured in one run, reported as medians and ratios."""
