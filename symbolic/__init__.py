"""quadland_symbolic: the model, the controllers and the C writers, built once in CasADi."""

#: When this package was first imported (``time.time_ns``): a source file written after it
#: may differ from the code this process runs (``quadland.engine.recall.remember``).
IMPORTED_NS = __import__("time").time_ns()
