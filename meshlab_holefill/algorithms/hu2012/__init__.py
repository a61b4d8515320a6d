"""algorithms.hu2012."""
