"""Helpers of the test suite that are not fixtures of the installed package."""
