"""The scene: its sections and their checks, TOML loading and --set overrides, the named materials,
the die profile and a user's mesh file as the scene describes them.
"""
