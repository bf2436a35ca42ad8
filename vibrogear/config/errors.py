"""The config layer's error: :class:`ConfigError` names the field path and the allowed
range.  One error or many: a check that can go on after a problem collects its errors
(:class:`ErrorList`) and raises them together, so ``vibrogear check`` shows every problem
it found in one run (up to :data:`MAX_ERRORS`), the first one's path as the error's path."""
from __future__ import annotations

__all__ = ["ConfigError", "ErrorList", "MAX_ERRORS"]

#: the most errors one run reports
MAX_ERRORS = 20


class ConfigError(ValueError):
    """Invalid input: names the field path and the allowed range.  ``errors``: the single
    errors it stands for (itself, or all of a collected list)."""

    def __init__(self, path: str, message: str, errors: list | None = None):
        self.path = path
        self.errors = errors if errors else [self]
        if errors and len(errors) > 1:
            shown = errors[:MAX_ERRORS]
            more = len(errors) - len(shown)
            text = "\n".join(str(e) for e in shown) + (
                f"\n... and {more} more (fix these and check again)" if more else "") + \
                f"\n({len(errors)} problems found)"
            super().__init__(text)
            self.message = text
        else:
            self.message = message
            super().__init__(f"{path}: {message}" if path else message)


class ErrorList:
    """Collects ConfigErrors: ``with errs.catch(): ...`` records one and goes on; ``raise_if``
    raises them together (nothing when none)."""

    def __init__(self):
        self.errors: list[ConfigError] = []

    def add(self, exc: ConfigError) -> None:
        self.errors.extend(exc.errors)

    def catch(self):
        errs = self

        class _Catch:
            def __enter__(self):
                return None

            def __exit__(self, tp, exc, tb):
                if tp is not None and issubclass(tp, ConfigError):
                    errs.add(exc)
                    return True
                return False
        return _Catch()

    def __bool__(self) -> bool:
        return bool(self.errors)

    def raise_if(self) -> None:
        if len(self.errors) == 1:
            raise self.errors[0]
        if self.errors:
            first = self.errors[0]
            raise ConfigError(first.path, first.message, errors=list(self.errors))
