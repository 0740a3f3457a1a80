"""Settings changed for a while and put back exactly as they were."""


class Overrides:
    """Context manager: `set(owner, attribute, value)` changes a setting and
    `keep(owner, *attributes)` marks settings that a change may alter as a
    side effect; each one's first value is recorded, and leaving restores
    them all, last recorded first."""

    def __init__(self):
        self._saved: dict[tuple[int, str], tuple[object, str, object]] = {}

    def keep(self, owner, *attributes: str) -> None:
        for attribute in attributes:
            self._saved.setdefault((owner.as_pointer(), attribute), (owner, attribute, getattr(owner, attribute)))

    def set(self, owner, attribute: str, value) -> None:
        self.keep(owner, attribute)
        setattr(owner, attribute, value)

    def restore(self) -> None:
        saved, self._saved = list(self._saved.values()), {}
        for owner, attribute, value in reversed(saved):
            if getattr(owner, attribute) != value:
                setattr(owner, attribute, value)

    def __enter__(self) -> "Overrides":
        return self

    def __exit__(self, *exc) -> None:
        self.restore()
