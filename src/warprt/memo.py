"""A small cache of values derived from an object (a Scene's BVH, its Mitsuba conversion), kept for
the next few calls with the same object, as Mitsuba keeps a loaded scene."""

from __future__ import annotations


class ObjectCache:
    """Least-recently-used, at most ``size`` entries. An entry is found by its key and kept only
    while it was made for the very object given (a new object may reuse a dead one's id)."""

    def __init__(self, size: int = 4):
        self.size = size
        self._entries: dict = {}

    def get(self, key, holder, make):
        """The value for ``key`` made from ``holder``, or ``make()``'s, which is then kept."""
        value = self.peek(key, holder)
        return self.put(key, holder, make()) if value is None else value

    def peek(self, key, holder):
        """The value kept for ``key`` and ``holder``, or None; as get(), it becomes the most recent."""
        entry = self._entries.pop(key, None)
        if entry is None or entry[0] is not holder:
            return None
        self._entries[key] = entry
        return entry[1]

    def put(self, key, holder, value):
        """Keep ``value`` for ``key`` made from ``holder``, replacing what was kept; returns it."""
        self._entries.pop(key, None)
        self._entries[key] = (holder, value)
        while len(self._entries) > self.size:
            self._entries.pop(next(iter(self._entries)))
        return value

    def clear(self):
        self._entries.clear()
