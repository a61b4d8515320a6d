"""pymeshlab integration."""
