"""Linear models beyond one FMU: a bench's Model Exchange plants with its controllers in the loop
(artibus.linear.bench, issue 43). One FMU alone: artibus.linearize."""
