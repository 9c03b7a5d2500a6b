"""Widgets the pages are built from (each a small view; none computes anything)."""
