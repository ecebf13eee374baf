"""The validation matrix behind ``make validate``: records with known truth, Monte-Carlo trials."""
