// A refused or failed API request: the HTTP status and the daemon's `error` text (PROTOCOL.md:
// every error body is {"error": "<message>"}); status 0 when the request never got an answer.
export class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.name = 'ApiError';
    this.status = status;
  }

  // The message of an error answer: its JSON `error`, else the status line.
  static fromBody(status, statusText, bodyText) {
    try {
      const body = JSON.parse(bodyText);
      if (body && typeof body.error === 'string') return new ApiError(status, body.error);
    } catch {
      // not JSON: fall through to the status line
    }
    return new ApiError(status, `HTTP ${status} ${statusText || ''}`.trim());
  }
}
