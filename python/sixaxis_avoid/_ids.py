"""The package's Gymnasium ids (registered by ``sixaxis_avoid/__init__.py``)."""

from __future__ import annotations

#: The grid world of the paper (``sixaxis_avoid.env.SixAxisAvoidEnv``).
ENV_ID = "SixAxisAvoid-v0"
#: The same, arm-aware (``arm_aware=True``).
ARM_ENV_ID = "SixAxisAvoidArm-v0"
#: The goal-conditioned variant (``sixaxis_avoid.env.SixAxisAvoidGoalEnv``).
GOAL_ENV_ID = "SixAxisAvoidGoal-v0"
#: The whole arm in joint space (``sixaxis_avoid.joint.SixAxisAvoidJointEnv``).
JOINT_ENV_ID = "SixAxisAvoidJoint-v0"
#: Its goal-conditioned variant (``sixaxis_avoid.joint.SixAxisAvoidJointGoalEnv``).
JOINT_GOAL_ENV_ID = "SixAxisAvoidJointGoal-v0"
