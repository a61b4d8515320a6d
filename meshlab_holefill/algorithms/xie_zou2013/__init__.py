"""algorithms.xie_zou2013."""
