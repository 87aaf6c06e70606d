"""Replacement tables: the table value and its JSON file format, generation by search, and the
enumeration of candidate sub-plans that generation uses.

Everything here works on any :class:`~selfrepair.robots.domain.Domain` passed in as a value: this
package imports ``robots.domain`` and ``robots.registry`` (to read a domain name in a file), never
a concrete robot, and never ``world``: a table is a property of a robot, not of a maze.
"""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
