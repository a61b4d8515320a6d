"""algorithms.brunton2009."""
