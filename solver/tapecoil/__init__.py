"""tapecoil: coiling and deployment of tape springs with FEniCSx."""

__version__ = "0.1.0"
