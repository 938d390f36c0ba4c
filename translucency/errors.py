"""Exception types of translucency.

Every error that a user can cause (bad parameters, bad files, bad light specifications) is raised as
a subclass of :class:`TranslucencyError` with one sentence that says what is wrong and how to fix it.
The CLI prints that sentence and exits non-zero; it never shows a traceback for these.
"""


class TranslucencyError(Exception):
    """Base class of every error translucency raises on purpose."""


class InvalidParameterError(TranslucencyError, ValueError):
    """A physical or numerical parameter is out of its valid range (medium, material, light, solver)."""


class UnknownMaterialError(TranslucencyError, KeyError):
    """A material name that is not in the catalogue."""

    def __str__(self) -> str:  # KeyError would print the message with quotes around it
        return str(self.args[0]) if self.args else ""


class MeshError(TranslucencyError, ValueError):
    """A mesh file or mesh array that cannot be used (unreadable, corrupt, empty, invalid values)."""
