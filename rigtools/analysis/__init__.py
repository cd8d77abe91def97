"""Signal analysis of Recordings: spectra, natural frequencies with damping, RMS, mesh orders."""

__all__: list[str] = []
