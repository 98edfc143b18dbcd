"""Pieces shared by every SARAS Python package, each implemented once."""
