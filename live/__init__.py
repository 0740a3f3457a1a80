"""Live caustics: the receivers' caustics follow the scene as the user works (session.py)."""

from .session import register, unregister

__all__ = ["register", "unregister"]
