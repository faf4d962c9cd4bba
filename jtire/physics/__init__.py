"""Force terms of the ring-of-shells model, one per file; `vector_field` assembles them."""
