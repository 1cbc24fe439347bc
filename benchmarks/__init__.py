"""Benchmarks and figures: they call only warprt's public API and the Mitsuba reference."""
