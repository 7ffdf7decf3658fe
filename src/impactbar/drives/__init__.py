"""Drives that are not functions of time: the valve of a hydraulic drifter switched by the piston's
position (theory §10). The system they drive is autonomous; its blow frequency is an output."""

from .switched import PositionSwitchedDrive as PositionSwitchedDrive

__all__ = ["PositionSwitchedDrive"]
