"""evaluation.papers."""
