"""The scene subsystem (paper section VI): game commands given to the teams, the per-team coach, the
automatic referee and the other judges. The scene *file* every subsystem reads is `simatch.config`."""
