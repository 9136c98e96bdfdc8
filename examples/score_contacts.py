"""Score contacts that come from anywhere (GraspIt!, another simulator, a robot).

The second Python example of the README; run it with ``python examples/score_contacts.py``.
"""

import numpy as np

import affordgrasp as ag
from affordgrasp.metrics import epsilon, hold_effort, use_force

# Two fingers pinching a 4 cm cube centred at the origin: points on the surface, the
# object's OUTWARD normals, the friction coefficient.
contacts = ag.ContactSet.from_arrays(
    points=[[0.02, 0, 0], [-0.02, 0, 0]], normals=[[1, 0, 0], [-1, 0, 0]], mu=0.5
)
centre = np.zeros(3)  # the object's centre of mass
print(epsilon(contacts, centre, r_max=0.0346))  # ε = 0: two point contacts never close
print(hold_effort(contacts, centre))  # N of normal force against 1 N of gravity along ±x, ±y, ±z
print(use_force(contacts, centre, use_point=[0, 0, 0.02], use_normal=[0, 0, 1]))
