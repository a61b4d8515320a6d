"""meshlab.mlx."""
