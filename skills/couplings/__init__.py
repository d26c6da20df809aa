"""The coupling-term library: one small class per behaviour, each with ``acceleration``.

Every class satisfies :class:`skills.couplings.term.CouplingTerm`: ``acceleration(state, target)``
returns additive (linear m/s^2, angular rad/s^2) accelerations for a pose DMP.

=============================  ===========================================================
:class:`LearntForcing`         a learnt skill's RBF forcing, on a shared transformation system
:class:`Saturated`             a group of terms, summed, faded and its norms limited
:class:`ObstacleSteering`      Hoffmann et al. 2009 steering with a distance factor
:func:`fit_obstacle_steering`  its parameters from avoidance demonstrations (Rai et al. 2014)
:class:`PotentialFieldAvoidance`  Park et al. 2008 dynamic potential on attached points
:class:`SphereObstacles`       its distance query to spheres in closed form
:class:`GraspMaintenance`      relative-space spring to the grasp geometry (Gams et al. 2014)
:class:`ForceTrackingGrasp`    the same, tracking a normal contact force
:class:`WorkspaceRepulsion`    box limits (after Gams et al. 2009)
:class:`JointLimitRepulsion`   joint limits through the task Jacobian
=============================  ===========================================================
"""

from skills.couplings.distance_queries import DistanceQuery, MovingPoints, SphereObstacles
from skills.couplings.forcing import LearntForcing
from skills.couplings.grasp import ForceTrackingGrasp, GraspMaintenance
from skills.couplings.limits import JointLimitRepulsion, WorkspaceRepulsion
from skills.couplings.potential import PotentialFieldAvoidance
from skills.couplings.saturated import Saturated
from skills.couplings.steering import ObstacleSteering, steering_accelerations
from skills.couplings.steering_fit import (
    AvoidanceDemo,
    SteeringFit,
    demonstrated_coupling,
    fit_obstacle_steering,
)

__all__ = [
    "AvoidanceDemo",
    "DistanceQuery",
    "ForceTrackingGrasp",
    "GraspMaintenance",
    "JointLimitRepulsion",
    "LearntForcing",
    "MovingPoints",
    "ObstacleSteering",
    "PotentialFieldAvoidance",
    "Saturated",
    "SphereObstacles",
    "SteeringFit",
    "WorkspaceRepulsion",
    "demonstrated_coupling",
    "fit_obstacle_steering",
    "steering_accelerations",
]
