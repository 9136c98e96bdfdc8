"""The grasp policy GP(p0, O): from a pregrasp to the contacts of a closed hand.

* ``pregrasp``: decoding p0 and the use direction d into hand frames and use rays;
* ``surface``: dense surface samples of an object (its side of hand-object collision);
* ``kernels``: the compiled approach and closing searches;
* ``policy``: approach, close, collect the contacts (statuses, ``simulate``).

Conventions: docs/conventions.md, "Pregrasp, use direction and grasp policy".
"""
