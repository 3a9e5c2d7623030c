"""What ``evotol check-mechanism`` checks and shows about a description."""
