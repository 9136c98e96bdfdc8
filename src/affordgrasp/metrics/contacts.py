"""Contact sets under the metrics' name: :class:`~affordgrasp.grasp.contacts.ContactSet`.

The type is defined by the grasp stage that produces contact sets
(:mod:`affordgrasp.grasp.contacts`); the metrics take them from any source.
"""

from __future__ import annotations

from ..grasp.contacts import ContactSet

__all__ = ["ContactSet"]
