"""What the swimmer is asked to do: free swimming, following a target, SWIM's goal reaching."""
from layered_swim.tasks.base import Task
from layered_swim.tasks.follow import FollowTarget
from layered_swim.tasks.free_swim import FreeSwim
from layered_swim.tasks.goal import GoalReaching

__all__ = ["Task", "FreeSwim", "FollowTarget", "GoalReaching"]
