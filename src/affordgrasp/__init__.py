"""affordgrasp: task-oriented grasp quality metrics, datasets and learning."""

__version__ = "0.1.0"
