"""Row-wise numpy helpers that every stage uses."""
