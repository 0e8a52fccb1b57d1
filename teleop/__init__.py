"""Operators that drive the robot (scripted now; device streams with the teleoperation issue) and
the online recorder that writes raw recordings."""
