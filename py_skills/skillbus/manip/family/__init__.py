"""The manipulation-command skill family (docs/manip.md): importing these modules
registers the skills."""
