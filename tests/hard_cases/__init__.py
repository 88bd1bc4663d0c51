"""Hard cases of sphere tracing (Hart 1996): one module per theme, each stating the expected
behaviour, its analytic answer and the tolerance it is held to."""
