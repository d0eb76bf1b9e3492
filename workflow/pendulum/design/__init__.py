"""What to film next: discovery's final model and the group's records in, predicted intervals for one more trial out."""
