"""What a person sees: map and localization pictures, the live view, progress bars."""
