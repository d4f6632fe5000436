"""The quantity table every pymunk module passes around (:data:`Values`); a linkage's
reactions are read by :func:`.linkage.reactions`."""

Values = dict[str, float]
