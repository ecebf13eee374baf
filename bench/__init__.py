"""Benchmarks run by `make bench` (not unit tests: nothing here asserts on timings)."""
