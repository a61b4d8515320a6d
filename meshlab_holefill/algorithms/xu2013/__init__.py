"""algorithms.xu2013."""
