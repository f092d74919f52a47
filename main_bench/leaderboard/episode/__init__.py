"""Pictures of one evaluated episode: its data, the top-down picture, the GIF and the message timeline."""
