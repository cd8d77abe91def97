"""Fixtures of the pipeline tests (defined in :mod:`pipeline_cases`)."""

from pipeline_cases import demo_source, whole_run

__all__ = ["demo_source", "whole_run"]
