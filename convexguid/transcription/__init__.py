"""Transcriptions: node sets, quadrature and differentiation matrices handed to formulations."""

from convexguid.transcription.mapped_chebyshev import MappedChebyshev

__all__ = ["MappedChebyshev"]
