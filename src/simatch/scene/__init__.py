"""The scene subsystem: scene files, game commands, coaches, the automatic referee and other judges."""
