"""Pictures and viewers: offscreen PNG rendering (matplotlib)."""

from .png import render_png

__all__ = ["render_png"]
