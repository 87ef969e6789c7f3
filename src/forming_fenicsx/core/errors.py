"""Exceptions that the command line turns into one clear message and a non-zero exit code."""


class SceneError(ValueError):
    """An invalid scene value: names the key and what is allowed."""

    def __init__(self, key: str, message: str):
        super().__init__(f"{key}: {message}")
        self.key = key
        self.message = message

    def __reduce__(self):
        """Picklable, so that rank 0's verdict can be broadcast to every rank."""
        return SceneError, (self.key, self.message)


class LinearSolveError(RuntimeError):
    """A linear solve of the iteration failed; PETSc's reason is the same on every rank."""
