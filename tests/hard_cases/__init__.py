"""Hard cases of sphere tracing (issue 6): one module per theme, each stating the expected
behaviour, its analytic answer and the tolerance it is held to."""
